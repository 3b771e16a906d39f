#pragma once
// What a coordinator's run is given and gives back: its options, its outcome, and the exception
// that stops it. Shared by the Coordinator (coordinator.h) and its internal state (state.h).

#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "runtime/node/lag.h"
#include "runtime/node/plan.h"
#include "runtime/record/record.h"
#include "runtime/rt/pacing.h"
#include "study/study.h"
#include "transport/transport.h"
#include "transport/unauthenticated.h"
#include "view/control_room.h"

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
  // The view's control room (view/control_room.h), polled once per step as stop_request is: each
  // press becomes a record event; an allowed HOLD goes to its nodes at once and holds the run (no
  // further step, messages and liveliness go on) until an allowed STOP stops it as the view's
  // stop does, its status naming who held it.
  view::ControlDesk* control = nullptr;
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
  // The loop thread's CPU time per step (RunState::step_cpu): median, p99, max, s.
  runtime::LagSummary step_cpu;
  // The run stopped for its machine, not for the test: its record could not be written (a full
  // disk, a file size limit, a writer left behind). The program exits 3 for it, as for any
  // environment fault.
  bool environment_fault = false;
};

}  // namespace rths::coordinator
