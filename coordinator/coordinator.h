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
//   loop       core::run_steps(), the one stepping loop the in-process simulation also runs: this
//              class is its restoring-force evaluator (exchange over the transport) and its hooks
//              (pacing before a step, record after it). Lockstep equals in process by construction.
//   lockstep   waits for every answer to step k (step_timeout), simulated time only.
//   real time  absolute deadlines every dt (Pacer with the deployment's wait policy: sleep,
//              sleep_then_spin, spin), the only timed wait between steps (feedback is stamped
//              and boxed on the receive thread meanwhile; other messages queue, stamped on
//              arrival, and are taken after the wait, before the commands); waits at most
//              feedback_wait_fraction * dt for the answers to step k, otherwise uses the newest
//              answer it has and records which step that answers; overruns, late feedback and
//              their worst streaks are counted and recorded per step.
//   servo      an emulator with a servo loop faster than the integrator (study.servo.rate) streams
//              a FEEDBACK per servo period in real time: the first for step k is its answer (lag,
//              freshness); later servo samples of step k replace the measurement (newest wins,
//              never counted as duplicates). Its servo periods and overruns arrive in heartbeats;
//              more overruns than max_overrun_fraction of its periods is also "completed with
//              deadline misses". Lockstep: the servo periods run in simulated time, one answer.
// Outcome: ok only when the run did what it was for. Not ok: diverged; a real-time run whose
// overruns exceed max_overrun_fraction of its steps ("completed with deadline misses"); any stop
// below; a run record that lost entries.
// Faults (what the coordinator does, within how many steps):
//   a node gives no fresh answer for max_missed_answers (3) consecutive real-time steps
//                  -> stops at that step: HOLD to the emulators, STOP to all, the node named.
//                     At most max_missed_answers - 1 steps are integrated on its old force.
//   an emulator answers HOLD (it held on its own: watchdog, rate limit) -> stops at once, naming
//   it. a node silent for liveliness_timeout (1 s; the slower second line, also in lockstep), no
//   lockstep answer within step_timeout, |u| or |v| beyond the limits, a commanded drift changing
//   by more than limits.max_displacement_step -> stops before the command is sent. the record's
//   writer fails a write (disk full, I/O error, file size limit) or falls more than its ring (4096
//   entries) behind -> stops within a step or two of it, naming the file and the reason; the record
//   is the readable prefix written before the failure. a stop request (options.stop_request: the
//   view's stop button) -> stops before the next step,
//                  status kStoppedFromView.
//   Every stop: HOLD to the emulators, STOP to all, the record closed with the reason and node.
//   an integrity fault (coordinator::FeedbackIntake: an answer as a node from a participant other
//   than the one that announced as it, or two different answers to one step) -> stops at the
//   loop's next look at the intake (within the step in lockstep), naming the node and both
//   arrivals.
//   rejects    foreign-run (and empty run id), garbage, duplicate, stale, out-of-order (incl. an
//              answer not echoing its step's command), unknown-node, not-entitled (a node's id on
//              another node's topic or from another writer than the one pinned at its
//              announcement; a coordinator's kind sent as a node) and out-of-range (a force or
//              drift not finite, beyond the limits) messages are counted and never applied.
// Trust: each node speaks on its own up topic; its first announcement pins its writer. An
// announcement never stops the run (once ready, or of the wrong kind, it is counted).
// Start-up heartbeats keep the nodes already assigned alive while late ones join.
// After the STOPs, each node's last heartbeat reports what it rejected, by cause
// (RunOutcome::node_rejects, the footer's node_rejects).
// Record: header, one StepRecord per step, events, the header again, footer (the second header
// keeps the record whole when its first copy is damaged), through runtime::AsyncRecordWriter:
// the loop only serialises into a preallocated ring slot; a writer thread does the I/O. A crash
// loses at most the entries still queued (the ring's capacity, 4096; in practice the writer is
// one or two entries behind). Every entry carries a CRC-32C (runtime/record.h). A record that
// cannot be written stops the run, as a fault below: nothing would be kept of it.
// Feedback: judged and decoded on the transport's receive thread (its inline handler) by
// coordinator::FeedbackIntake into one wait-free LatestBox per node; the loop takes the newest
// without a lock or a copy, and is woken once per step, when the step's last answer is in.
// Real-time safety of a step: the record entry, the feedback slots, the lag vectors and the
// outgoing command message (runtime::pack_into) are reused or reserved up front, and the receive
// thread's decode of a feedback allocates nothing once warm; what still allocates is a message
// other than feedback (heartbeats, taken off the transport's queue) and, rarely, an event.
// mlockall and pinning of the loop thread when the deployment asks. Each step records
// command_latency (wake-up to the last command written); bench/runtime_bench prints it.
// pin_loop: the loop thread alone on loop_cpu (runtime::isolate_calling_thread_on_cpu; rths
// launch starts the nodes off it). The figures measured are in the README ("Real time").

#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/study.h"
#include "runtime/lag.h"
#include "runtime/pacing.h"
#include "runtime/plan.h"
#include "runtime/record.h"
#include "transport/transport.h"
#include "transport/unauthenticated.h"

namespace rths::coordinator {

// Stops the run: thrown inside the loop (by the coordinator's own parts or by a StepDriver) with
// the reason and the label of the participant at fault (empty: none). The run then sends HOLD to
// the emulators and STOP to all, and closes the record with the reason.
struct RunAborted : std::runtime_error {
  RunAborted(const std::string& why, std::string node)
      : std::runtime_error(why), node(std::move(node)) {}
  std::string node;
};

// Where a run's trial states come from. Empty: core::run_steps with the study's integrator.
// Otherwise an outside integrator (an OpenSees model over TCP) drives the coordinator's evaluator
// and hooks under run_steps' contract: result sized for the motion's steps and truncated to the
// completed ones, row 0 the rest state, then for each step k >= 1 hooks.before_step(k),
// evaluator.set_time(k dt), evaluator.trial(u, v, nullptr), row k stored, hooks.after_step(k),
// evaluator.commit(); k stays below the motion's sample count (the record's ground acceleration).
using StepDriver = std::function<void(core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                                      core::SimulationResult& result)>;

struct CoordinatorOptions {
  std::string run_id;                     // must be non-empty
  std::string case_name;                  // empty: deployment.case_name, else the reference case
  std::filesystem::path record;           // empty: no record file
  runtime::PacingClock* clock = nullptr;  // real time; null = CLOCK_MONOTONIC
  double divergence_bound = 1.0e3;        // m, as core::SimulationOptions
  // Real time: the platform check the run starts under, kept in the record's header.
  std::optional<runtime::PlatformSummary> platform;
  StepDriver driver;  // empty: the study's integrator (core::run_steps)
  // Sees each record entry on the record's writer thread (the live view); needs `record`.
  runtime::RecordObserver* record_observer = nullptr;
  // Set from another thread (the view's stop button): the loop stops before its next step as for
  // any fault, HOLD then STOP, with the status kStoppedFromView. Read once per step (relaxed).
  const std::atomic<bool>* stop_request = nullptr;
  // What the transport dropped unread for want of a MAC (DdsEndpoint::unauthenticated), read once
  // after the run for the outcome and the record's last event; empty: nothing to read.
  std::function<transport::Unauthenticated()> unauthenticated;
};

inline constexpr const char* kStoppedFromView = "stopped from the view";

struct LinkLagStats {
  int node_id = 0;
  std::string label;
  runtime::LagSummary round_trip, injected;  // s
};

struct RunOutcome {
  bool ok = false;
  std::string status;             // "completed" or why it stopped
  std::string failed_node;        // label of the node that caused the stop, if one did
  core::SimulationResult result;  // steps completed (up to the failure)
  runtime::Counters counters;
  std::vector<LinkLagStats> links;
  std::vector<runtime::NodeRejects> node_rejects;  // per node, what it rejected (its last report)
  // What the transport dropped unread for want of a MAC (CoordinatorOptions::unauthenticated).
  transport::Unauthenticated unauthenticated;
  double wall_seconds = 0.0;
  double max_lateness = 0.0;  // s, real time
};

class Coordinator {
 public:
  // Throws std::invalid_argument for a deployment that does not fit the study, an implicit
  // integrator, or a dt beyond the stability limit.
  Coordinator(core::PreparedStudy prepared, transport::Endpoint& endpoint,
              CoordinatorOptions options);
  ~Coordinator();
  RunOutcome run();
  const runtime::DeploymentPlan& plan() const { return plan_; }

  // The coordinator's state (coordinator/state.h, internal to rths_coordinator).
  struct State;

 private:
  std::unique_ptr<State> state_;
  runtime::DeploymentPlan plan_;
};

}  // namespace rths::coordinator
