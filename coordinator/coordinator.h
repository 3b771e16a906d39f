#pragma once
// The coordinator: the integrator loop of a distributed hybrid test, over any transport.
//
//   start-up   wait for every node of the deployment to announce; send each its Assign (its part
//              of the one study config); wait until all are READY. Timeout: error naming each node
//              that never announced or never became ready.
//   each step  exactly core::simulate()'s sequence: load p_{k+1} = -M iota a_g[k+1]; the
//              integrator's single trial goes out as COMMANDs (drifts, drift velocities, t_{k+1});
//              storey shear = numerical (nodes, or local) + experimental (emulators), then DOF
//              forces. Doubles cross the wire unchanged, so lockstep equals the in-process run
//              bit for bit.
//   lockstep   waits for every answer to step k (step_timeout), simulated time only.
//   real time  absolute deadlines every dt (Pacer); between steps it takes messages off the wire
//              until 150 us before the deadline (so receive stamps are not delayed by its sleep),
//              then clock_nanosleep; waits at most feedback_wait_fraction * dt for
//              the answers to step k, otherwise uses the newest answer it has and records which
//              step that answers; overruns are counted and recorded per step.
//   safety     a node silent for liveliness_timeout, a missing answer, or a command beyond the
//              displacement / velocity limits stops the run: HOLD to the emulators, STOP to all,
//              the record is closed with the reason and the node, outcome.ok = false.
//   rejects    foreign-run, garbage, duplicate, stale, out-of-order, unknown-node messages are
//              counted and never applied.
// Record: header, one StepRecord per step (flushed), events, footer.
// Real-time safety: the step allocates (message payload strings, the record entry) and writes
// the record synchronously (one write + flush per step, so a crash loses at most one step); it
// does no other blocking I/O.

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "core/study.h"
#include "runtime/lag.h"
#include "runtime/pacing.h"
#include "runtime/plan.h"
#include "runtime/record.h"
#include "transport/transport.h"

namespace rths::coordinator {

struct CoordinatorOptions {
  std::string run_id;                 // must be non-empty
  std::string case_name;              // empty: deployment.case_name, else the reference case
  std::filesystem::path record;       // empty: no record file
  runtime::PacingClock* clock = nullptr;  // real time; null = CLOCK_MONOTONIC
  double divergence_bound = 1.0e3;    // m, as core::SimulationOptions
};

struct LinkLagStats {
  int node_id = 0;
  std::string label;
  runtime::LagSummary round_trip, injected;  // s
};

struct RunOutcome {
  bool ok = false;
  std::string status;        // "completed" or why it stopped
  std::string failed_node;   // label of the node that caused the stop, if one did
  core::SimulationResult result;  // steps completed (up to the failure)
  runtime::Counters counters;
  std::vector<LinkLagStats> links;
  double wall_seconds = 0.0;
  double max_lateness = 0.0;  // s, real time
};

// Generates "<host>-<pid>-<realtime ns>".
std::string make_run_id();

class Coordinator {
 public:
  // Throws std::invalid_argument for a deployment that does not fit the study, an implicit
  // integrator, or a dt beyond the stability limit.
  Coordinator(core::PreparedStudy prepared, transport::Endpoint& endpoint,
              CoordinatorOptions options);
  ~Coordinator();
  RunOutcome run();
  const runtime::DeploymentPlan& plan() const { return plan_; }

 private:
  struct State;
  std::unique_ptr<State> state_;
  runtime::DeploymentPlan plan_;
};

}  // namespace rths::coordinator
