#pragma once
// The one stepping loop of a hybrid simulation, and the in-process run built on it.
//
// run_steps() is the only loop that integrates a hybrid test: in process (simulate(), with
// HybridRestoring), lockstep over a transport and real time (the coordinator, with an evaluator that
// exchanges commands and feedback with nodes, and hooks that pace and record). So "lockstep equals
// in process" holds by construction: both run this code with the same doubles.
//
//   k = 0       p_0 = -M iota a_g[0]; integrator initialised at rest (u = v = 0, r = 0);
//               hooks.after_step(0)
//   k = 1..N-1  hooks.before_step(k)            (real time: wait for deadline k)
//               restoring.set_time(k dt); p_k = -M iota a_g[k]; integrator.step(p_k, restoring)
//               row k of the result <- u, v, a (the kept DOFs), command, realised, measured force
//               (actuators); max |u|, max |v| over every DOF and the base shear when asked
//               stop, diverged, when any |u| > options.divergence_bound (or NaN)
//               stop, held (result.held), when the evaluator's hold() names a reason (a force
//               predictor past its bound)
//               hooks.after_step(k)             (record, limits; false stops the run)
// Input: a ground motion already at the integration step dt (m/s^2).
// Output: histories at t_k = k dt, k = 0..N-1 (N = number of motion samples), SI units.

#include <string>
#include <vector>

#include "core/force_predictor.h"
#include "core/ground_motion.h"
#include "core/integrators.h"
#include "core/link_answers.h"
#include "core/substructure.h"

namespace rths::core {

struct HybridSetup {
  StructuralModel model;
  IntegratorKind integrator = IntegratorKind::kExplicitNewmark;
  double dt = 0.0;  // s
  bool allow_unstable = false;
  HybridPartition partition;
  std::vector<DelayChain> delays;  // one per actuator (partition.actuator_storeys); may be empty,
                                   // built for the servo period dt / servo_substeps
  int servo_substeps = 1;          // servo periods per integrator step (core::Actuator)
  // A force predictor per actuator (core/force_predictor.h), or none; empty: none at all.
  std::vector<std::optional<PredictorParameters>> predictors;
  // The network between the integrator and each actuator's lab (core/link_answers.h), one per
  // actuator, or none: which answer each step uses. simulate() applies it unless it replays.
  std::vector<LinkModel> links;
};

struct SimulationResult {
  double dt = 0.0;
  std::vector<double> time;  // s
  Mat displacement;          // m, rows = steps, cols = kept DOFs (relative to ground)
  Mat velocity;              // m/s
  Mat acceleration;          // m/s^2 (relative)
  // The DOF (0-based) of each column of displacement, velocity and acceleration, ascending;
  // empty: every DOF, column i DOF i.
  std::vector<int> dofs;
  // Per step when SimulationOptions::peaks, over every DOF (kept or not): the largest |u| (m) and
  // |v| (m/s), and the first DOF (0-based) that holds it; what a limit is judged on without the
  // history of every DOF. Empty otherwise.
  std::vector<double> peak_displacement, peak_velocity;
  std::vector<int> peak_displacement_dof, peak_velocity_dof;
  // N per step when SimulationOptions::base_shear: iota^T M (a + iota a_g), the inertial forces'
  // sum along the ground motion, equal and opposite to the ground's reaction; else empty.
  std::vector<double> base_shear;
  Mat command, realised, measured_force;  // per actuator: m, m, N
  bool diverged = false;                  // stopped early: |u| exceeded the divergence bound
  // Per actuator (N): the force predictor's error e at each step (0 without one).
  Mat prediction_error;
  // Per actuator, its force predictor's model at the run's end with the terms' standard errors
  // (ForcePredictor::model_text); empty where it has none. In-process runs only.
  std::vector<std::string> predictor_models;
  // Stopped early by a force predictor past its bound: which link and why; empty otherwise.
  std::string held;
  std::size_t steps() const { return time.size(); }
  // The column holding DOF `dof` (0-based), or -1 when the run did not keep it.
  Eigen::Index column_of_dof(int dof) const;
  // Keeps the first `steps` rows of every history (a run that stopped early).
  void truncate(std::size_t steps);
};

struct SimulationOptions {
  // Stop, marking the result diverged, when any |u| exceeds this (m). Protects sweeps from
  // unstable cases running to inf/NaN.
  double divergence_bound = 1.0e3;
  // The DOFs (0-based, ascending, unique) whose u, v and a the result keeps at every step; empty:
  // every DOF. A large model's run keeps what its recorders ask for (study/recorders.h), so
  // memory and the loop's stores are O(kept), not O(n) a step.
  std::vector<int> kept_dofs;
  bool base_shear = false;  // fill SimulationResult::base_shear
  bool peaks = false;       // fill SimulationResult's per-step peaks over every DOF
};

// What a runtime adds around each step. Either hook may throw to abort the run; the loop then
// truncates the result to the completed steps before the exception leaves it.
// What the loop does around each step (pacing, recording, live view). Called on the loop thread,
// between steps: before_step may block until the step's deadline (real time) and nothing else;
// after_step must not block or allocate (the record and the view copy into preallocated slots
// and do their I/O on threads of their own).
class StepHooks {
 public:
  virtual ~StepHooks() = default;
  // Before step k (k >= 1) is integrated. Real time waits for its deadline here.
  virtual void before_step(std::size_t /*k*/) {}
  // After row k of `result` is stored (k = 0 is the initial state). False stops the run
  // (the step stays in the result).
  virtual bool after_step(std::size_t /*k*/, const SimulationResult& /*result*/) { return true; }
};

// Runs the loop. `result` is resized for every step of the motion on entry and truncated to the
// steps completed on return, or when an exception leaves the loop. Throws std::invalid_argument
// when dt is not > 0, the motion's dt differs from setup.dt, the motion is empty, or a kept DOF is
// outside the model or out of order. Allocates only on entry (the result, the integrator).
void run_steps(const HybridSetup& setup, const GroundMotion& motion_at_dt,
               HybridEvaluator& restoring, StepHooks& hooks, const SimulationOptions& options,
               SimulationResult& result);

// Throws std::invalid_argument when dt is beyond the integrator's limit (unless allowed), when
// the motion's dt differs from setup.dt, or when an implicit integrator meets a delay stage or a
// replay. `answers`: the answers a distributed run used, replayed (answer_replay.h); empty rows:
// every step on its own answer. `hooks`: what the loop does around each step (a run's progress),
// none when null.
SimulationResult simulate(const HybridSetup& setup, const GroundMotion& motion_at_dt,
                          const SimulationOptions& options = {}, const AnswerSchedule& answers = {},
                          StepHooks* hooks = nullptr);

}  // namespace rths::core
