#include "coordinator/coordinator.h"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "coordinator/answer_verdict.h"
#include "coordinator/deadline_verdict.h"
#include "coordinator/flood_blame.h"
#include "coordinator/state.h"
#include "runtime/record/node_health.h"
#include "runtime/record/realtime_verdict.h"

namespace rths::coordinator {

namespace {

// A case's link is the network of an in-process run; across nodes the network is real or the
// nodes' own lags. A run that dropped it silently would not be the case it names.
void refuse_case_link(const core::HybridSetup& setup, const std::string& case_name) {
  if (!setup.links.empty())
    throw std::invalid_argument(
        "case '" + case_name +
        "' has a link (Case.link), the network of an in-process run (rths run); a distributed "
        "run's network is its nodes' receive_lag and send_lag (rths sites: its links): give the "
        "lag there, or run a case without a link");
}

}  // namespace

Coordinator::Coordinator(study::PreparedStudy prepared, transport::Endpoint& endpoint,
                         CoordinatorOptions options)
    : state_(std::make_unique<RunState>(std::move(prepared), endpoint, std::move(options))) {
  RunState& s = *state_;
  if (s.options.run_id.empty()) throw std::invalid_argument("coordinator: empty run id");
  s.deployment = s.prepared.config.deployment();
  s.case_name = !s.options.case_name.empty() ? s.options.case_name : s.deployment.case_name();
  const config::Case& study_case = study::find_case(s.prepared.config, s.case_name);
  s.case_name = study_case.name();
  s.setup = study::setup_for_case(s.prepared, study_case);
  refuse_case_link(s.setup, s.case_name);
  if (!core::is_explicit(s.setup.integrator))
    throw std::invalid_argument("integrator " + core::to_string(s.setup.integrator) +
                                " is implicit; a distributed run needs an explicit integrator");
  core::check_stability(s.setup.integrator, core::max_omega(s.setup.model), s.setup.dt,
                        s.setup.allow_unstable);
  s.deployment = runtime::with_default_nodes(s.deployment, s.setup);
  plan_ = runtime::plan_deployment(s.setup, s.deployment);
  runtime::check_node_stages(plan_, s.setup.dt, s.prepared.base_dir);
  s.real_time = s.deployment.clock() == config::Deployment::REAL_TIME;
  const std::size_t steps = s.prepared.motion.acceleration.size();
  std::vector<IntakeNode> intake_nodes;
  for (const runtime::NodePlan& n : plan_.nodes) {
    RunState::Node& node = s.nodes[n.spec.id()];
    node.plan = &n;
    node.awaited = s.awaits_answers_of(n.spec);
    if (s.real_time && node.awaited) node.wait_judge.emplace(s.answer_wait());
    if (s.real_time) node.window.emplace(s.deployment, n.spec, s.setup.dt);
    s.lags.reserve(n.spec.id(), steps);  // no growth on the loop
    s.endpoint.listen_to(n.spec.id());
    intake_nodes.push_back({n.spec.id(), static_cast<int>(n.storeys.size()),
                            runtime::drives_actuators(n.spec.kind()), node.awaited});
  }
  s.step_cpu.reserve(steps);  // no growth on the loop
  s.intake = std::make_unique<FeedbackIntake>(s.options.run_id, intake_nodes,
                                              s.deployment.limits().max_displacement());
  const int storeys = static_cast<int>(s.setup.partition.numerical.size());
  const int actuators = static_cast<int>(s.setup.partition.actuator_storeys.size());
  s.assembly = s.setup.partition.assembly();
  if (plan_.numerical_local)
    s.local_numerical = std::make_unique<core::NumericalSubstructure>(s.setup.partition);
  s.drift = core::Vec::Zero(storeys);
  s.limits = std::make_unique<CommandLimits>(s.deployment.limits(),
                                             s.setup.partition.actuator_storeys, storeys);
  s.drift_velocity = core::Vec::Zero(storeys);
  s.shear = core::Vec::Zero(storeys);
  s.force = core::Vec::Zero(s.setup.partition.dofs());
  s.command_drift = core::Vec::Zero(actuators);
  s.realised_drift = core::Vec::Zero(actuators);
  s.measured = core::Vec::Zero(actuators);
  // The case's force predictors, the same blocks core::simulate builds (core/force_predictor.h).
  s.predictors = core::PredictorSet(s.setup.predictors, s.setup.dt,
                                    core::actuator_specimens(s.setup.partition));
  s.used_force = core::Vec::Zero(actuators);
  s.command_rate = core::Vec::Zero(actuators);
  s.prediction_error_ = core::Vec::Zero(actuators);
  s.answer_steps.assign(static_cast<std::size_t>(actuators), -1);
}

Coordinator::~Coordinator() = default;

namespace {

// The run's lifecycle, as run() calls it: activate -> loop -> judge -> deactivate -> report.

// The record's header, every node ready, the real-time thread prepared.
void activate(RunState& s) {
  s.write_header();
  s.start_up();
  s.event("all " + std::to_string(s.nodes.size()) + " nodes ready (" +
          std::string(s.real_time ? "real time" : "lockstep") + ", case " + s.case_name + ")");
  if (s.real_time) s.prepare_real_time_thread();
  for (const auto& [id, node] : s.nodes)
    if (!node.awaited)
      s.event("not waiting for the answers of " + node.plan->label() + ": its link injects a " +
              std::to_string(1e3 * RunState::injected_round_trip(node.plan->spec)) +
              " ms round trip, longer than the loop's wait of " +
              std::to_string(1e3 * s.answer_wait()) + " ms; each step uses its newest answer");
}

// The loop's set-up (the integrator factorised, the kept histories sized; an outside driver's
// own, such as an OpenSees model's) runs after every node is assigned, and a node whose
// coordinator is silent for its orphan timeout (from its Assign) holds and leaves. So while it
// runs, a thread of its own sends the heartbeat every heartbeat period: the nodes wait however long
// the set-up takes, and a coordinator that dies meanwhile sends none. Stopped (joined) before the
// hook of step 0 runs, so from then on the loop thread is the only one that sends.
class SetUpHeartbeat {
 public:
  explicit SetUpHeartbeat(RunState& s)
      : thread_([this, &s] {
          const auto period =
              std::chrono::duration<double>(runtime::heartbeat_period(s.deployment));
          std::unique_lock lock(mutex_);
          while (!stop_) {
            s.send_heartbeat_when_due();
            stopped_.wait_for(lock, period, [this] { return stop_; });
          }
        }) {}
  SetUpHeartbeat(const SetUpHeartbeat&) = delete;
  SetUpHeartbeat& operator=(const SetUpHeartbeat&) = delete;
  ~SetUpHeartbeat() { stop(); }
  void stop() {
    {
      std::lock_guard guard(mutex_);
      stop_ = true;
    }
    stopped_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable stopped_;
  bool stop_ = false;
  std::thread thread_;  // last: starts once the members it uses exist
};

// The run's hooks, with the set-up heartbeat stopped before step 0's (the set-up is over).
class AfterSetUp final : public core::StepHooks {
 public:
  AfterSetUp(RunState& s, SetUpHeartbeat& heartbeat) : s_(s), heartbeat_(heartbeat) {}
  void before_step(std::size_t k) override { s_.before_step(k); }
  bool after_step(std::size_t k, const core::SimulationResult& result) override {
    if (k == 0) heartbeat_.stop();
    return s_.after_step(k, result);
  }

 private:
  RunState& s_;
  SetUpHeartbeat& heartbeat_;
};

// core::run_steps (or the options' outside StepDriver) with this run as its evaluator and hooks.
// Feedback is judged and boxed on the transport's receive thread; the loop is woken once a step's
// answers are all in (or a fault was raised). The handler is removed (waiting out a running call)
// before this returns. Per step the loop keeps what the study's recorders ask for (the DOFs of
// study/recorders.h kept_dofs), as rths run does: the record is O(recorded), not O(n), a step.
void loop(RunState& s, core::SimulationResult& result) {
  core::SimulationOptions options =
      study::kept_by_recorders(s.prepared.recorders, s.deployment.limits());
  options.divergence_bound = s.options.divergence_bound;
  s.endpoint.set_inline_handler([&s](const transport::Message& m) {
    if (m.kind != runtime::FEEDBACK) return false;
    if (s.intake->offer(m)) s.endpoint.interrupt();
    return true;
  });
  struct RemoveHandler {
    transport::Endpoint& endpoint;
    ~RemoveHandler() { endpoint.set_inline_handler(nullptr); }
  } remove_handler{s.endpoint};
  SetUpHeartbeat heartbeat(s);
  AfterSetUp hooks(s, heartbeat);
  if (s.options.driver)
    s.options.driver(s, hooks, result);
  else
    core::run_steps(s.setup, s.prepared.motion, s, hooks, options, result);
}

// A loop that ran to its end: diverged, deadline misses (the loop's, by the one real-time verdict
// that identify and the view apply to its record, or a servo's), a node that answered too few
// steps (answer_shortfall), or completed.
void judge(RunState& s, const runtime::Pacer& pacer, RunOutcome& outcome) {
  const core::SimulationResult& result = outcome.result;
  if (result.diverged)
    s.event("diverged: |u| = " +
            std::to_string(result.displacement.bottomRows(1).cwiseAbs().maxCoeff()) + " m");
  outcome.ok = !result.diverged;
  outcome.status = result.diverged ? "diverged" : "completed";
  const double tolerance = runtime::max_overrun_fraction(s.deployment);
  std::optional<std::string> misses;
  if (s.real_time && !result.diverged)
    misses = runtime::deadline_verdict({result.steps() > 0 ? result.steps() - 1 : 0,
                                        pacer.overruns(), pacer.worst_overrun_streak()},
                                       runtime::deadline_rule(s.deployment, s.setup.dt));
  for (const auto& [id, node] : s.nodes)
    if (outcome.ok && !misses)
      misses = servo_deadline_misses(node.plan->label(), node.servo_overruns, node.servo_ticks,
                                     tolerance);
  const double min_answers = runtime::min_answer_fraction(s.deployment);
  for (const auto& [id, node] : s.nodes)
    if (s.real_time && outcome.ok && !misses && min_answers >= 0) {
      // Answers to the last steps of a link slower than a step are still on the wire at the end.
      const auto in_flight = static_cast<std::uint64_t>(std::ceil(
                                 RunState::injected_round_trip(node.plan->spec) / s.setup.dt)) +
                             1;
      const std::uint64_t due = node.judged_steps > in_flight ? node.judged_steps - in_flight : 0;
      misses = answer_shortfall(id, std::min(node.answers, due), due, min_answers);
    }
  if (misses) {
    outcome.ok = false;
    outcome.status = *misses;
    s.event(outcome.status);
  }
}

// Whom a HOLD went to, for its event: "actuator emulators", "controller nodes" or both (a run
// with no node of either kind announced still says the emulators, as the plan has them).
std::string hold_receivers(const RunState& s) {
  bool emulators = false, controllers = false;
  for (const auto& [id, node] : s.nodes) {
    if (!node.announced) continue;
    emulators = emulators || node.plan->spec.kind() == config::NodeSpec::ACTUATOR_EMULATOR;
    controllers = controllers || node.plan->spec.kind() == config::NodeSpec::CONTROLLER;
  }
  if (controllers && emulators) return "actuator emulators and controller nodes";
  return controllers ? "controller nodes" : "actuator emulators";
}

// HOLD to the emulators after a failure; STOP to every node that announced, addressed to it
// after its HOLD on the same topic, so the STOP cannot overtake the HOLD (DDS orders per topic
// only). A node that never announced was never assigned and ignores all but ASSIGN. Then waits
// (at most kFinalReportWait) for each node's last heartbeat, which carries what it rejected.
void deactivate(RunState& s, bool failed, const std::string& status) {
  if (failed) {
    spdlog::error("run {} stopped at step {}: {}", s.options.run_id, s.step, status);
    runtime::Hold hold;
    hold.set_reason(status);
    for (auto& [id, node] : s.nodes)
      if (runtime::drives_actuators(node.plan->spec.kind()) && node.announced)
        s.send(id, runtime::HOLD, s.step, hold);
    s.event("HOLD sent to the " + hold_receivers(s) + ": " + status);
  }
  runtime::Stop stop;
  stop.set_reason(status);
  for (auto& [id, node] : s.nodes)
    if (node.announced) s.send(id, runtime::STOP, s.step, stop);
  // A controller node holds its rig before its STOP frame and its final report.
  auto wait = std::chrono::duration<double>(kFinalReportWait);
  for (const auto& [id, node] : s.nodes)
    if (node.plan->spec.kind() == config::NodeSpec::CONTROLLER)
      wait = std::max(
          wait,
          std::chrono::duration<double>(kFinalReportWait + std::chrono::milliseconds(500)) +
              std::chrono::duration<double>(node.plan->spec.controller().hold_time_ms() * 1e-3));
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(wait);
  const auto all_reported = [&s] {
    for (const auto& [id, node] : s.nodes)
      if (node.announced && !node.final_report) return false;
    return true;
  };
  while (!all_reported() && Clock::now() < until) {
    try {
      s.pump(std::chrono::milliseconds(5));
    } catch (const RunAborted&) {
      // The run is over: what a node says now (its own HOLD) changes nothing.
    }
  }
}

// Counters, link lag and what each node rejected, into the outcome.
void report(const RunState& s, const runtime::Pacer& pacer, RunOutcome& outcome) {
  const std::size_t completed = outcome.result.steps();
  runtime::RejectCounters rejected = s.rejected;
  rejected.add(s.intake->rejected());
  rejected.fill(outcome.counters);
  // Never seen by the coordinator's own checks: the transport dropped them before any handler.
  if (s.options.unauthenticated) outcome.unauthenticated = s.options.unauthenticated();
  outcome.counters.set_unauthenticated(outcome.unauthenticated.count);
  outcome.counters.set_overruns(pacer.overruns());
  outcome.counters.set_late_feedback(s.late_feedback);
  outcome.counters.set_worst_overrun_streak(pacer.worst_overrun_streak());
  outcome.counters.set_worst_late_streak(s.worst_late_streak);
  outcome.counters.set_steps(completed > 0 ? completed - 1 : 0);
  outcome.max_lateness = pacer.max_lateness();
  outcome.step_cpu = runtime::summarize(s.step_cpu);
  for (const auto& [id, node] : s.nodes) {
    outcome.counters.set_servo_ticks(outcome.counters.servo_ticks() + node.servo_ticks);
    outcome.counters.set_servo_overruns(outcome.counters.servo_overruns() + node.servo_overruns);
    runtime::NodeRejects& node_rejects = outcome.node_rejects.emplace_back();
    node_rejects.set_node_id(id);
    node_rejects.set_label(node.plan->label());
    *node_rejects.mutable_rejected() = node.rejects;
    node_rejects.set_final(node.final_report);
    if (node.plan->spec.kind() == config::NodeSpec::CONTROLLER)
      *node_rejects.mutable_controller() = node.controller;
    if (node.window)
      *node_rejects.mutable_answer_age() =
          node.ages.summary(static_cast<double>(node.window->steps(s.time)), s.setup.dt);
    LinkLagStats stats;
    stats.node_id = id;
    stats.label = node.plan->label();
    const auto series = s.lags.links().find(id);
    if (series != s.lags.links().end()) {
      stats.round_trip = series->second.round_trip_summary();
      stats.injected = series->second.injected_summary();
    }
    outcome.links.push_back(stats);
  }
}

// The controller links, as their final reports say: a frame from a wrong source or a rejected
// one fails the run (someone else speaks on the rig's network, or the rig sent what it must
// not); lost and late frames fail it beyond the answer tolerance (1 - min_answer_fraction of the
// frames sent), and are said in an event within it.
void judge_links(RunState& s, RunOutcome& outcome) {
  const double min_answers = runtime::min_answer_fraction(s.deployment);
  for (const runtime::NodeRejects& n : outcome.node_rejects) {
    const auto verdict = runtime::link_verdict(n);
    if (!verdict) continue;
    const runtime::ControllerReport& r = n.controller();
    const bool rejected = runtime::controller_rejected(r) > 0;
    const double missing = static_cast<double>(r.lost() + r.late());
    const bool too_many =
        min_answers >= 0 && missing > (1.0 - min_answers) * static_cast<double>(r.frames_sent());
    if (!rejected && !too_many) {
      s.event(*verdict + " (within the answer tolerance)");
      continue;
    }
    outcome.ok = false;
    outcome.status = "failed: " + *verdict;
    outcome.failed_node = n.label();
    s.event(outcome.status);
    return;
  }
}

// A real-time run that failed (not by diverging: that is the physics) names an unauthenticated
// flood its receivers dropped meanwhile.
void blame_flood(RunState& s, RunOutcome& outcome) {
  std::vector<std::pair<std::string, std::uint64_t>> receivers{
      {"coordinator", outcome.unauthenticated.count}};
  for (const runtime::NodeRejects& n : outcome.node_rejects)
    receivers.emplace_back(n.label(), n.rejected().unauthenticated());
  const auto flood =
      unauthenticated_flood(receivers, outcome.wall_seconds, outcome.unauthenticated.last);
  if (!flood) return;
  outcome.status += *flood;
  s.event("failed" + *flood);
}

// A record that lost entries fails the run; the footer closes it.
void close_record(RunState& s, RunOutcome& outcome) {
  if (!s.record) return;
  if (s.record->dropped() > 0 && !s.record_failed) {
    outcome.ok = false;
    outcome.status += "; the run record lost " + std::to_string(s.record->dropped()) +
                      " entries (its writer fell more than " +
                      std::to_string(s.record->capacity()) + " entries behind)";
  }
  if (outcome.unauthenticated.count > 0)
    s.event(std::to_string(outcome.unauthenticated.count) +
            " messages dropped unread as unauthenticated (no valid MAC under the run secret); "
            "newest: " +
            outcome.unauthenticated.last);
  if (s.header_entry.has_header()) s.append_waiting(s.header_entry);
  runtime::RecordEntry entry;
  runtime::RunFooter& f = *entry.mutable_footer();
  f.set_ok(outcome.ok);
  f.set_status(outcome.status);
  f.set_failed_node(outcome.failed_node);
  *f.mutable_counters() = outcome.counters;
  f.set_diverged(outcome.result.diverged);
  f.set_wall_seconds(outcome.wall_seconds);
  for (const runtime::NodeRejects& n : outcome.node_rejects) *f.add_node_rejects() = n;
  s.append_waiting(entry);
  try {
    s.record->close();
  } catch (const std::runtime_error& e) {  // a write failed: the run kept nothing after it
    outcome.ok = false;
    outcome.environment_fault = true;
    if (!s.record_failed) outcome.status += std::string("; ") + e.what();
  }
  outcome.environment_fault |= s.record_failed;
}

}  // namespace

RunOutcome Coordinator::run() {
  RunState& s = *state_;
  const auto wall_start = Clock::now();
  RunOutcome outcome;
  if (!s.options.record.empty())
    s.record = std::make_unique<runtime::AsyncRecordWriter>(s.options.record);
  if (s.record) s.record->set_observer(s.options.record_observer);
  runtime::MonotonicClock monotonic;
  runtime::Pacer pacer(s.options.clock ? *s.options.clock : monotonic, s.setup.dt,
                       runtime::wait_policy(s.deployment));
  s.pacer = &pacer;
  bool failed = false;
  try {
    activate(s);
    loop(s, outcome.result);
    judge(s, pacer, outcome);
  } catch (const RunAborted& e) {
    failed = true;
    outcome.status = e.what();
    outcome.failed_node = e.node;
  } catch (const std::exception& e) {
    // Transport or record failures: still hold the actuators and close the record.
    failed = true;
    outcome.status = std::string("internal error: ") + e.what();
  }
  deactivate(s, failed, outcome.status);
  report(s, pacer, outcome);
  if (outcome.ok) judge_links(s, outcome);
  outcome.wall_seconds = seconds_since(wall_start);
  if (!outcome.ok && s.real_time && !outcome.result.diverged) blame_flood(s, outcome);
  close_record(s, outcome);
  s.pacer = nullptr;
  return outcome;
}

}  // namespace rths::coordinator
