#pragma once
// What each case of a study keeps and writes (Study.recorders, proto/config.proto), resolved
// against the model: the channels of the results file and the DOFs the run keeps per step.
//
// Input: the study's recorders, the model's DOF count n and its experimental DOFs.
// Output: RecorderPlan, every index 0-based:
//   channels     one per quantity asked for, in the recorders' order, each once: a DOF's u (m),
//                v (m/s) or a (m/s^2) relative to the ground; a drift u[dof] - u[from_dof] (m,
//                from_dof -1: the ground); the actuators (command m, measured m, force N); the
//                base shear (N). A channel asked for twice keeps the steps of both (every = the
//                greatest common divisor of theirs).
//   kept_dofs    what core::run_steps keeps per step (SimulationOptions::kept_dofs): empty (every
//                DOF) for n <= kAllDofsLimit, else every DOF a channel reads, the response DOF
//                (the top, n - 1) and the experimental DOFs, ascending.
// Without recorders (the defaults): n <= kAllDofsLimit keeps every DOF's displacement and the
// actuators, every step (the table every run wrote before recorders); a larger model the
// actuators and the displacement of the experimental DOFs, DOFs 1, n/4, n/2, 3n/4 (rounded down,
// at least 1) and the top, and `defaults` says so in one line.
// A run keeps step k of a channel when k % every == 0 (every >= 1).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/simulation.h"
#include "core/substructure.h"
#include "rths/proto/config.pb.h"

namespace rths::study {

inline constexpr int kAllDofsLimit = 200;

struct RecordedChannel {
  enum class Kind { kDisplacement, kVelocity, kAcceleration, kDrift, kActuators, kBaseShear };
  Kind kind = Kind::kDisplacement;
  int dof = -1;       // 0-based; a drift's upper end; -1 for actuators and base shear
  int from_dof = -1;  // a drift's lower end, 0-based; -1 = the ground
  int every = 1;      // steps between kept samples, >= 1
  bool keeps(std::size_t step) const { return step % static_cast<std::size_t>(every) == 0; }
};

struct RecorderPlan {
  std::vector<RecordedChannel> channels;
  std::vector<int> kept_dofs;  // empty: every DOF
  bool base_shear = false;     // a channel asks for the base shear
  // The defaults of a model past kAllDofsLimit, in one line ("recorders: none given; 1000 DOFs,
  // so the results keep ..."); empty when the study has recorders or the model is small.
  std::string defaults;
  // Whether any channel keeps step k (a row of the results table).
  bool keeps(std::size_t step) const;
  // The results table's columns of one case: one a channel, three per actuator for kActuators.
  std::size_t columns_per_case(std::size_t actuators) const;
};

// The checks that need no model: each recorder asks for something, DOFs and range ends >= 1,
// last >= first, step and every >= 0, a drift's ends differ. Throws std::invalid_argument
// "SOURCE: recorders[i].field ..." naming the field and the value.
void validate_recorders(const config::Study& study, const std::string& source);

// The plan for a model of `dofs` DOFs whose experimental parts sit at `experimental_dofs`
// (0-based). Throws std::invalid_argument naming the recorder's field when a DOF is past the
// model ("recorders[0].dofs[2]: DOF 1001 is outside the model's 1..1000").
RecorderPlan plan_recorders(const config::Study& study, int dofs,
                            const std::vector<int>& experimental_dofs);

// What each simulation of the study keeps per step (core::SimulationOptions), in process and in
// the coordinator's loop alike: the plan's kept DOFs and base shear, and the per-step peaks over
// every DOF when `limits` sets a displacement or velocity limit (what it is judged on).
core::SimulationOptions kept_by_recorders(const RecorderPlan& plan,
                                          const config::SafetyLimits& limits);

// Bytes a run of `cases` cases holds per step of the motion, at most (what prepare_study checks
// against the memory limit before anything is allocated): per simulation (the lag-free run and
// each case) 8 (time) + 24 a kept DOF (u, v, a; every DOF when the plan keeps all of the model's
// `dofs`) + 32 an actuator (command, realised, force, prediction error) + 24 with peaks (limits
// set) + 8 with the base shear; per case 8 (its response); the results table 8 a cell; the
// motion 16 (as read and at dt). Against measured resident memory (docs/performance.md): an SDOF,
// one actuator, two cases, 5.6 million steps held 262 bytes a step; this gives 304.
std::uint64_t run_bytes_per_step(const RecorderPlan& plan, int dofs, std::size_t actuators,
                                 std::size_t cases, bool peaks);

// The DOFs (0-based, ascending) an experimental part moves: an actuator's storey or DOF and, for
// a storey, the floor below it; an element's every term.
std::vector<int> experimental_dofs(const core::HybridPartition& partition);

}  // namespace rths::study
