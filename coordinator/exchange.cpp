// The coordinator's messages with the nodes and the step's exchange (see state.h).
#include "coordinator/state.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "runtime/node/hold_cause.h"

namespace rths::coordinator {

using runtime::Verdict;

namespace {

// Decodes the payload into `payload`, or counts the message as garbage: false then.
template <class T>
bool unpack_or_count(const transport::Message& message, T& payload,
                     runtime::RejectCounters& rejected) {
  if (runtime::unpack(message, payload)) return true;
  rejected.count(Verdict::kGarbage);
  return false;
}

}  // namespace

bool RunState::pump(std::chrono::nanoseconds timeout) {
  auto message = endpoint.receive(timeout);
  if (!message) return false;
  if (message->kind == runtime::FEEDBACK) {
    intake->offer(*message);
    return true;
  }
  Verdict verdict = runtime::check_envelope(*message, options.run_id);
  const auto it = nodes.find(message->node_id);
  if (verdict == Verdict::kAccept && it == nodes.end()) verdict = Verdict::kUnknownNode;
  if (verdict == Verdict::kAccept) verdict = runtime::check_sender(*message, it->second.writer);
  if (verdict != Verdict::kAccept) {
    rejected.count(verdict);
    return true;
  }
  apply(*message, it->second);
  return true;
}

void RunState::apply(const transport::Message& message, Node& node) {
  switch (message.kind) {
    case runtime::ANNOUNCE: {
      runtime::Announce announce;
      if (unpack_or_count(message, announce, rejected)) on_announce(message, announce, node);
      return;
    }
    case runtime::READY: {
      runtime::Ready ready;
      if (!unpack_or_count(message, ready, rejected)) return;
      node.last_seen = Clock::now();
      if (!ready.error().empty())
        throw RunAborted("could not build its part: " + ready.error(), node.plan->label());
      node.ready = true;
      return;
    }
    case runtime::HOLD: {
      // A node held on its own (its watchdog, limits or a fault): the test cannot go on. In a run
      // held from the view no command leaves, so only a command watchdog's HOLD is expected and
      // recorded there; any other ends the held run as it ends any run, naming the node.
      runtime::Hold hold;
      if (!unpack_or_count(message, hold, rejected)) return;
      const std::string held = "held on its own at its step " + std::to_string(message.step);
      if (!held_from_view.empty() && runtime::is_command_watchdog_hold(hold.reason())) {
        event(node.plan->label() + " " + held + " while the run is held: " + hold.reason());
        return;
      }
      throw RunAborted(held + ": " + hold.reason() +
                           (held_from_view.empty() ? "" : " (while held: " + held_from_view + ")"),
                       node.plan->label());
    }
    case runtime::HEARTBEAT: {
      runtime::Heartbeat heartbeat;
      if (!unpack_or_count(message, heartbeat, rejected)) return;
      node.last_seen = Clock::now();
      node.servo_ticks = heartbeat.servo_ticks();
      node.servo_overruns = heartbeat.servo_overruns();
      if (heartbeat.has_controller()) node.controller = heartbeat.controller();
      node.rejects = heartbeat.rejected_by_cause();
      node.final_report = node.final_report || heartbeat.final();
      return;
    }
    default:
      // A coordinator's own kinds (ASSIGN, COMMAND, STOP) sent as a node: nobody may.
      rejected.count(Verdict::kNotEntitled);
      return;
  }
}

void RunState::on_announce(const transport::Message& message, const runtime::Announce& announce,
                           Node& node) {
  // Once ready, or announcing as another kind than the deployment's, an announcement changes
  // nothing: counted, never a reason to stop (anyone can send one).
  if (node.ready || announce.kind() != node.plan->spec.kind()) {
    rejected.count(Verdict::kNotEntitled);
    return;
  }
  node.last_seen = Clock::now();
  if (!node.announced) {
    spdlog::info("{} announced from {} pid {}", node.plan->label(), announce.host(),
                 announce.pid());
    // The node's writer is pinned: from now on only it may speak as this node.
    node.writer = message.writer;
    intake->pin(node.plan->spec.id(), message.writer);
  }
  node.announced = true;
  send_assign(node);
}

void RunState::send_assign(const Node& node) {
  runtime::Assign assign;
  assign.set_schema_version(runtime::kSchemaVersion);
  *assign.mutable_study() = prepared.config;
  assign.set_base_dir(prepared.base_dir.string());
  assign.set_case_name(case_name);
  *assign.mutable_node() = node.plan->spec;
  assign.set_dt(setup.dt);
  for (int s : node.plan->storeys) assign.add_storeys(s);
  for (int a : node.plan->actuators) assign.add_actuators(a);
  assign.set_heartbeat_period(runtime::heartbeat_period(deployment));
  // A node outlives a silent coordinator only a little longer than the coordinator tolerates it.
  assign.set_orphan_timeout(std::max(2.0, 2.0 * runtime::judged_liveliness_timeout(deployment)));
  send(node.plan->spec.id(), runtime::ASSIGN, 0, assign);
}

void RunState::check_liveliness() {
  const double limit = runtime::judged_liveliness_timeout(deployment);
  for (auto& [id, node] : nodes) {
    const double silent = seconds_since(node.last_seen);
    if (silent > limit)
      throw RunAborted(node.plan->label() + " silent for " + std::to_string(silent) +
                           " s (liveliness timeout " + std::to_string(limit) + " s)",
                       node.plan->label());
  }
  send_heartbeat_when_due();
}

void RunState::send_heartbeat_when_due() {
  if (seconds_since(last_heartbeat_sent) <= runtime::heartbeat_period(deployment)) return;
  runtime::Heartbeat hb;
  hb.set_last_step(step);
  send(transport::kBroadcastId, runtime::HEARTBEAT, step, hb);
  last_heartbeat_sent = Clock::now();
}

void RunState::start_up() {
  const double timeout = runtime::start_timeout(deployment);
  const auto start = Clock::now();
  for (auto& [id, node] : nodes) node.last_seen = start;
  for (;;) {
    bool all = true;
    for (auto& [id, node] : nodes) all = all && node.ready;
    if (all) return;
    if (seconds_since(start) > timeout) {
      std::string missing;
      for (auto& [id, node] : nodes) {
        if (node.ready) continue;
        missing += (missing.empty() ? "" : "; ") + node.plan->label() +
                   (node.announced ? " announced but never became ready" : " never announced");
      }
      throw RunAborted("start-up timed out after " + std::to_string(timeout) + " s: " + missing,
                       "");
    }
    pump(std::chrono::milliseconds(20));
    // Nodes already assigned wait for the late ones: the heartbeat keeps them from leaving.
    send_heartbeat_when_due();
  }
}

double RunState::injected_round_trip(const config::NodeSpec& spec) {
  return spec.receive_lag().one_way_delay() + spec.send_lag().one_way_delay();
}

double RunState::answer_wait() const {
  return runtime::feedback_wait_fraction(deployment) * setup.dt;
}

bool RunState::awaits_answers_of(const config::NodeSpec& spec) const {
  return !real_time || runtime::awaits_answers(deployment, spec, setup.dt);
}

void RunState::absorb() {
  if (const IntegrityFault* fault = intake->fault())
    throw RunAborted(fault->what, nodes.at(fault->node_id).plan->label());
  for (auto& [id, node] : nodes) {
    const ArrivedFeedback* arrived = intake->take(id);
    if (!arrived) continue;
    node.last_seen = Clock::now();
    const bool new_answer = arrived->answers != node.answers;
    node.last_answer = arrived->answered_step;
    node.answers = arrived->answers;
    if (!new_answer || !node.wait_judge) continue;
    if (const auto change = node.wait_judge->step(arrived->link.round_trip()))
      switch_answer_wait(id, node, *change);
  }
}

void RunState::switch_answer_wait(int id, Node& node, const AnswerWait::Switch& change) {
  node.awaited = change.waiting;
  intake->set_awaited(id, change.waiting);
  const std::string measured = ": their round trip (median " +
                               std::to_string(1e6 * change.median_round_trip) + " us of the last " +
                               std::to_string(AnswerWait::kJudged) + ") is ";
  const std::string wait = std::to_string(1e6 * answer_wait()) + " us wait";
  event(change.waiting
            ? "waiting again for the answers of " + node.plan->label() + measured +
                  "well within the loop's " + wait
            : "not waiting for the answers of " + node.plan->label() + measured +
                  "longer than the loop's " + wait + "; each step uses its newest answer");
}

namespace {

// Each node's COMMAND of this step: its storeys' drifts (m) and drift velocities (m/s), stamped
// so that its answer must echo the stamp. No allocation once warm (pack_into).
void send_commands(RunState& run) {
  for (auto& [id, node] : run.nodes) {
    run.command_message.Clear();
    run.command_message.set_time(run.time);
    for (int s : node.plan->storeys) {
      run.command_message.add_drift(run.drift[s]);
      run.command_message.add_drift_velocity(run.drift_velocity[s]);
    }
    runtime::pack_into(run.outgoing, run.options.run_id, id, runtime::COMMAND, run.step,
                       run.command_message);
    run.outgoing.sent_ns = transport::realtime_ns();
    run.intake->command_sent(id, run.outgoing.sent_ns);  // its answer must echo this stamp
    run.endpoint.send(run.outgoing);
  }
}

// Storey shear = numerical + experimental (the order core::HybridRestoring uses) from the
// newest answers, and per actuator its command, realised and measured values and, with a
// predictor, which step its answer answered.
void take_answers(RunState& run) {
  for (auto& [id, node] : run.nodes) {
    if (node.plan->spec.kind() != config::NodeSpec::SUBSTRUCTURE) continue;
    for (std::size_t i = 0; i < node.plan->storeys.size(); ++i)
      run.shear[node.plan->storeys[i]] = run.force_of(node, i);
  }
  const auto& storeys = run.setup.partition.actuator_storeys;
  for (auto& [id, node] : run.nodes) {
    if (!runtime::drives_actuators(node.plan->spec.kind())) continue;
    for (std::size_t i = 0; i < node.plan->actuators.size(); ++i) {
      const int a = node.plan->actuators[i];
      const int s = storeys[a];
      run.command_drift[a] = run.drift[s];
      run.realised_drift[a] = run.realised_of(node, i);
      run.measured[a] = run.force_of(node, i);
      if (!run.predictors.empty()) {
        const std::int64_t answered = run.intake->latest(id).answered_step;
        run.answer_steps[static_cast<std::size_t>(a)] =
            answered > 0 ? static_cast<long>(answered) : -1;
        run.command_rate[a] = run.drift_velocity[s];
      }
    }
  }
}

}  // namespace

const core::Vec& RunState::trial(const core::Vec& u, const core::Vec& v, core::Mat* tangent) {
  if (tangent) throw std::invalid_argument("the distributed runtime needs an explicit integrator");
  if (auto violation = limits->check_state(u, v)) throw RunAborted(*violation, "");
  assembly.drifts(u, drift);
  assembly.drifts(v, drift_velocity);
  if (auto violation = limits->check_rate(drift)) throw RunAborted(*violation, "");
  send_commands(*this);
  commands_written = Clock::now();
  if (local_numerical) {
    local_numerical->trial(drift, shear, nullptr);
  } else {
    shear.setZero();
  }
  collect();
  take_answers(*this);
  const auto& storeys = setup.partition.actuator_storeys;
  if (predictors.empty()) {
    core::assemble_storey_forces(assembly, storeys, measured, shear, force);
    return force;
  }
  const int exceeded = predictors.apply(command_drift, command_rate, answer_steps, realised_drift,
                                        measured, used_force, prediction_error_);
  if (exceeded >= 0) {
    // The fail-safe HOLDs on RunAborted, naming the link the predictor sits on.
    for (auto& [id, node] : nodes) {
      if (!runtime::drives_actuators(node.plan->spec.kind())) continue;
      for (int a : node.plan->actuators)
        if (a == exceeded)
          throw RunAborted(
              core::predictor_hold_reason(predictors, exceeded, "link to " + node.plan->label()),
              node.plan->label());
    }
  }
  core::assemble_storey_forces(assembly, storeys, used_force, shear, force);
  return force;
}

double RunState::force_of(const Node& node, std::size_t i) {
  const runtime::Feedback& f = intake->latest(node.plan->spec.id()).feedback;
  const int index = static_cast<int>(i);
  return index < f.force_size() ? f.force(index) : 0.0;
}

double RunState::realised_of(const Node& node, std::size_t i) {
  const runtime::Feedback& f = intake->latest(node.plan->spec.id()).feedback;
  const int index = static_cast<int>(i);
  return index < f.realised_size() ? f.realised(index) : 0.0;
}

void RunState::collect() {
  if (real_time) {
    // Wait part of the step for this step's answers, then go with the newest available.
    const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(answer_wait()));
    for (;;) {
      absorb();
      bool all = true;
      for (auto& [id, node] : nodes) all = all && (!node.awaited || node.last_answer == step);
      if (all) break;
      const auto left = until - Clock::now();
      if (left <= Clock::duration::zero()) break;
      pump(left);
    }
    while (pump(std::chrono::nanoseconds::zero())) {}
    absorb();
    judge_answers(runtime::max_missed_answers(deployment, setup.dt));
    check_liveliness();
    return;
  }
  const auto start = Clock::now();
  const double timeout = runtime::step_timeout(deployment);
  // The intake wakes the loop (interrupt) once the last answer to the step is in.
  for (;;) {
    absorb();
    int outstanding = 0;
    for (auto& [id, node] : nodes) outstanding += node.last_answer != step ? 1 : 0;
    if (outstanding == 0) return;
    pump(std::chrono::milliseconds(10));
    check_liveliness();
    if (seconds_since(start) > timeout) {
      std::string missing, first;
      for (auto& [id, node] : nodes)
        if (node.last_answer != step) {
          missing += (missing.empty() ? "" : ", ") + node.plan->label();
          if (first.empty()) first = node.plan->label();
        }
      throw RunAborted("no answer to step " + std::to_string(step) + " within " +
                           std::to_string(timeout) + " s from " + missing,
                       first);
    }
  }
}

void RunState::judge_answer_age(Node& node) {
  if (!node.window) return;
  const std::int64_t age = step - node.last_answer;
  node.ages.step(age);
  // Before a node's first answer nothing old is applied (the specimen is at rest): a start on a
  // busy machine may take longer than the window, so the first answer gets the liveliness
  // timeout; a node that never answers is stopped then, not only by the answer shortfall after
  // the run.
  const std::int64_t window =
      node.answers > 0 ? node.window->steps(time)
                       : std::max(node.window->steps(time),
                                  static_cast<std::int64_t>(std::ceil(
                                      runtime::judged_liveliness_timeout(deployment) / setup.dt)));
  if (age <= window) return;
  const auto ms = [this](std::int64_t steps) {
    return std::to_string(static_cast<double>(steps) * setup.dt * 1e3) + " ms";
  };
  throw RunAborted(
      (node.answers == 0 ? std::string("no answer yet")
                         : "its newest answer is to step " + std::to_string(node.last_answer)) +
          " at step " + std::to_string(step) + ": " + std::to_string(age) + " steps (" + ms(age) +
          ") old, beyond its answer window of " + std::to_string(window) + " steps (" + ms(window) +
          "); an answer that old is never applied",
      node.plan->label());
}

void RunState::judge_answers(int max_missed) {
  for (auto& [id, node] : nodes) {
    if (node.last_answer != step) {
      ++late_feedback;
      if (static_cast<std::uint64_t>(++node.late_streak) > worst_late_streak)
        worst_late_streak = static_cast<std::uint64_t>(node.late_streak);
    } else {
      node.late_streak = 0;
    }
    // Missing = no fresh answer at all this step (an answer to an older step, as a link
    // slower than a step delivers, is fresh). Counted once the node has answered: before
    // that, start-up and liveliness cover it.
    const bool fresh = node.answers != node.answers_before_step;
    node.fresh_steps += fresh ? 1 : 0;
    ++node.judged_steps;
    node.answers_before_step = node.answers;
    node.missed_streak = fresh || node.answers == 0 ? 0 : node.missed_streak + 1;
    if (node.missed_streak >= max_missed)
      throw RunAborted(
          "no answer for " + std::to_string(node.missed_streak) + " consecutive steps (steps " +
              std::to_string(step - node.missed_streak + 1) + " to " + std::to_string(step) +
              "; its newest answers step " + std::to_string(node.last_answer) + ")",
          node.plan->label());
    judge_answer_age(node);
  }
}

}  // namespace rths::coordinator
