#include "coordinator/coordinator.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "core/simulation.h"
#include "runtime/schema.h"
#include "runtime/validation.h"

namespace rths::coordinator {
namespace {

using Clock = std::chrono::steady_clock;
using runtime::Verdict;

// Thrown inside the loop when the run must stop; caught by run().
struct RunAborted : std::runtime_error {
  RunAborted(const std::string& why, std::string node)
      : std::runtime_error(why), node(std::move(node)) {}
  std::string node;
};

// Real time: stop draining the transport this long before a deadline and sleep the rest with
// clock_nanosleep (a waitset's timed wait is less precise).
constexpr std::int64_t kDrainMarginNs = 150'000;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

std::string make_run_id() {
  char host[128] = {};
  gethostname(host, sizeof host - 1);
  return std::string(host) + "-" + std::to_string(getpid()) + "-" +
         std::to_string(transport::realtime_ns());
}

struct Coordinator::State : core::RestoringEvaluator {
  core::PreparedStudy prepared;
  core::HybridSetup setup;
  std::string case_name;
  transport::Endpoint& endpoint;
  CoordinatorOptions options;
  const runtime::DeploymentPlan* plan = nullptr;
  config::Deployment deployment;
  bool real_time = false;

  // Per node.
  struct Node {
    const runtime::NodePlan* plan;
    bool announced = false, ready = false;
    Clock::time_point last_seen;
    std::int64_t last_answer = 0;  // step of the newest accepted feedback
    runtime::Feedback feedback;    // newest accepted
    runtime::LinkSample link;
    std::vector<double> round_trips, injected;
  };
  std::map<int, Node> nodes;
  runtime::RejectCounters rejected;
  std::uint64_t late_feedback = 0;

  // Evaluator state (sized once).
  core::StoreyAssembly assembly{1};
  std::unique_ptr<core::NumericalSubstructure> local_numerical;
  core::Vec drift, drift_velocity, shear, force, command, realised, measured;
  std::int64_t step = 0;
  double time = 0.0;
  runtime::Command command_message;
  std::unique_ptr<runtime::RecordWriter> record;
  Clock::time_point last_heartbeat_sent;

  State(core::PreparedStudy p, transport::Endpoint& e, CoordinatorOptions o)
      : prepared(std::move(p)), endpoint(e), options(std::move(o)) {}

  std::string label(int id) const {
    const auto it = nodes.find(id);
    return it != nodes.end() ? it->second.plan->label() : "node " + std::to_string(id);
  }

  void send(int node_id, runtime::MessageKind kind, std::int64_t at_step,
            const google::protobuf::MessageLite& payload) {
    endpoint.send(runtime::pack(options.run_id, node_id, kind, at_step, payload));
  }

  void event(const std::string& what) {
    spdlog::info("step {}: {}", step, what);
    if (!record) return;
    runtime::RecordEntry entry;
    entry.mutable_event()->set_step(step);
    entry.mutable_event()->set_what(what);
    record->write(entry);
  }

  // Takes one message off the transport and applies it if valid. False on timeout.
  bool pump(std::chrono::nanoseconds timeout) {
    auto message = endpoint.receive(timeout);
    if (!message) return false;
    const auto it = nodes.find(message->node_id);
    // Announcements carry the node's expected run id, empty when it was started without one.
    const bool announce = message->kind == runtime::ANNOUNCE &&
                          (message->run_id.empty() || message->run_id == options.run_id);
    Verdict verdict = announce ? Verdict::kAccept : runtime::check_envelope(*message, options.run_id);
    if (verdict == Verdict::kAccept && it == nodes.end()) verdict = Verdict::kUnknownNode;
    if (verdict != Verdict::kAccept) {
      rejected.count(verdict);
      return true;
    }
    Node& node = it->second;
    switch (message->kind) {
      case runtime::ANNOUNCE: {
        runtime::Announce announce_payload;
        if (!runtime::unpack(*message, announce_payload)) {
          rejected.count(Verdict::kGarbage);
          return true;
        }
        if (node.ready) return true;  // a late or forged announcement changes nothing
        if (announce_payload.kind() != node.plan->spec.kind())
          throw RunAborted(node.plan->label() + " announced itself as " +
                               runtime::node_kind_name(announce_payload.kind()) +
                               " (pid " + std::to_string(announce_payload.pid()) + " on " +
                               announce_payload.host() + ")",
                           node.plan->label());
        node.last_seen = Clock::now();
        if (!node.announced)
          spdlog::info("{} announced from {} pid {}", node.plan->label(), announce_payload.host(),
                       announce_payload.pid());
        node.announced = true;
        if (!node.ready) send_assign(node);
        return true;
      }
      case runtime::READY: {
        runtime::Ready ready;
        if (!runtime::unpack(*message, ready)) {
          rejected.count(Verdict::kGarbage);
          return true;
        }
        node.last_seen = Clock::now();
        if (!ready.error().empty())
          throw RunAborted("could not build its part: " + ready.error(), node.plan->label());
        node.ready = true;
        return true;
      }
      case runtime::FEEDBACK: {
        const std::int64_t newest = step;  // nothing newer was ever commanded
        const Verdict order = runtime::check_step(message->step, node.last_answer, newest);
        if (order != Verdict::kAccept) {
          rejected.count(order);
          return true;
        }
        runtime::Feedback feedback;
        const int expected = static_cast<int>(node.plan->storeys.size());
        const bool emulator = node.plan->spec.kind() == config::NodeSpec::ACTUATOR_EMULATOR;
        if (!runtime::unpack(*message, feedback) || feedback.force_size() != expected ||
            (emulator && feedback.realised_size() != expected)) {
          rejected.count(Verdict::kGarbage);
          return true;
        }
        node.last_seen = Clock::now();
        node.last_answer = message->step;
        node.feedback = std::move(feedback);
        runtime::LinkSample& link = node.link;
        link.set_node_id(node.plan->spec.id());
        link.set_answered_step(message->step);
        link.set_injected_lag(node.feedback.injected_lag());
        link.set_round_trip(static_cast<double>(message->received_ns - message->echo_ns) * 1e-9);
        link.set_one_way_down(
            static_cast<double>(node.feedback.command_received_ns() - message->echo_ns) * 1e-9);
        link.set_one_way_up(static_cast<double>(message->received_ns - message->sent_ns) * 1e-9);
        node.round_trips.push_back(link.round_trip());
        node.injected.push_back(link.injected_lag());
        return true;
      }
      case runtime::HEARTBEAT:
        node.last_seen = Clock::now();
        return true;
      default:
        return true;  // kinds a coordinator never acts on
    }
  }

  void send_assign(const Node& node) {
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
    assign.set_orphan_timeout(std::max(2.0, 2.0 * runtime::liveliness_timeout(deployment)));
    send(node.plan->spec.id(), runtime::ASSIGN, 0, assign);
  }

  void check_liveliness() {
    const double limit = runtime::liveliness_timeout(deployment);
    for (auto& [id, node] : nodes) {
      const double silent = seconds_since(node.last_seen);
      if (silent > limit)
        throw RunAborted(node.plan->label() + " silent for " + std::to_string(silent) +
                             " s (liveliness timeout " + std::to_string(limit) + " s)",
                         node.plan->label());
    }
    if (seconds_since(last_heartbeat_sent) > runtime::heartbeat_period(deployment)) {
      runtime::Heartbeat hb;
      hb.set_last_step(step);
      send(transport::kBroadcastId, runtime::HEARTBEAT, step, hb);
      last_heartbeat_sent = Clock::now();
    }
  }

  void start_up() {
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
    }
  }

  // ---- RestoringEvaluator: one exchange per step ----
  const core::Vec& trial(const core::Vec& u, const core::Vec& v, core::Mat* tangent) override {
    if (tangent)
      throw std::invalid_argument("the distributed runtime needs an explicit integrator");
    check_limits(u, v);
    assembly.drifts(u, drift);
    assembly.drifts(v, drift_velocity);
    for (auto& [id, node] : nodes) {
      command_message.Clear();
      command_message.set_time(time);
      for (int s : node.plan->storeys) {
        command_message.add_drift(drift[s]);
        command_message.add_drift_velocity(drift_velocity[s]);
      }
      send(id, runtime::COMMAND, step, command_message);
    }
    if (local_numerical) {
      local_numerical->trial(drift, shear, nullptr);
    } else {
      shear.setZero();
    }
    collect();
    // Storey shear = numerical + experimental, the order core::HybridRestoring uses.
    for (auto& [id, node] : nodes) {
      if (node.plan->spec.kind() != config::NodeSpec::SUBSTRUCTURE) continue;
      for (std::size_t i = 0; i < node.plan->storeys.size(); ++i)
        shear[node.plan->storeys[i]] = force_of(node, i);
    }
    const auto& storeys = setup.partition.actuator_storeys;
    for (auto& [id, node] : nodes) {
      if (node.plan->spec.kind() != config::NodeSpec::ACTUATOR_EMULATOR) continue;
      for (std::size_t i = 0; i < node.plan->actuators.size(); ++i) {
        const int a = node.plan->actuators[i];
        const int s = storeys[a];
        command[a] = drift[s];
        realised[a] = realised_of(node, i);
        measured[a] = force_of(node, i);
      }
    }
    for (std::size_t a = 0; a < storeys.size(); ++a) shear[storeys[a]] += measured[a];
    assembly.dof_forces(shear, force);
    return force;
  }

  // Before a node's first answer (real time, lag longer than the wait) the specimen is at rest.
  static double force_of(const Node& node, std::size_t i) {
    const int index = static_cast<int>(i);
    return index < node.feedback.force_size() ? node.feedback.force(index) : 0.0;
  }
  static double realised_of(const Node& node, std::size_t i) {
    const int index = static_cast<int>(i);
    return index < node.feedback.realised_size() ? node.feedback.realised(index) : 0.0;
  }

  void commit() override {
    if (local_numerical) local_numerical->commit();
  }
  bool repeatable() const override { return false; }

  void check_limits(const core::Vec& u, const core::Vec& v) const {
    const auto& limits = deployment.limits();
    for (int i = 0; i < u.size(); ++i) {
      if (limits.max_displacement() > 0 && !(std::abs(u[i]) <= limits.max_displacement()))
        throw RunAborted("safety limit: |u| of DOF " + std::to_string(i + 1) + " = " +
                             std::to_string(u[i]) + " m exceeds " +
                             std::to_string(limits.max_displacement()) + " m; command not sent",
                         "");
      if (limits.max_velocity() > 0 && !(std::abs(v[i]) <= limits.max_velocity()))
        throw RunAborted("safety limit: |v| of DOF " + std::to_string(i + 1) + " = " +
                             std::to_string(v[i]) + " m/s exceeds " +
                             std::to_string(limits.max_velocity()) + " m/s; command not sent",
                         "");
    }
  }

  void collect() {
    if (real_time) {
      // Wait part of the step for this step's answers, then go with the newest available.
      const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(
                                                runtime::feedback_wait_fraction(deployment) *
                                                setup.dt));
      for (;;) {
        bool all = true;
        for (auto& [id, node] : nodes) all = all && node.last_answer == step;
        if (all) break;
        const auto left = until - Clock::now();
        if (left <= Clock::duration::zero()) break;
        pump(left);
      }
      while (pump(std::chrono::nanoseconds::zero())) {
      }
      for (auto& [id, node] : nodes)
        if (node.last_answer != step) ++late_feedback;
      check_liveliness();
      return;
    }
    const auto start = Clock::now();
    const double timeout = runtime::step_timeout(deployment);
    // Be woken once all outstanding answers are in, not once per answer.
    struct ResetThreshold {
      transport::Endpoint& endpoint;
      ~ResetThreshold() { endpoint.set_wake_threshold(1); }
    } reset{endpoint};
    for (;;) {
      int outstanding = 0;
      for (auto& [id, node] : nodes) outstanding += node.last_answer != step ? 1 : 0;
      if (outstanding == 0) return;
      endpoint.set_wake_threshold(outstanding);
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
};

Coordinator::Coordinator(core::PreparedStudy prepared, transport::Endpoint& endpoint,
                         CoordinatorOptions options)
    : state_(std::make_unique<State>(std::move(prepared), endpoint, std::move(options))) {
  State& s = *state_;
  if (s.options.run_id.empty()) throw std::invalid_argument("coordinator: empty run id");
  s.deployment = s.prepared.config.deployment();
  s.case_name = !s.options.case_name.empty() ? s.options.case_name : s.deployment.case_name();
  const config::Case& study_case = runtime::find_case(s.prepared.config, s.case_name);
  s.case_name = study_case.name();
  s.setup = core::setup_for_case(s.prepared, study_case);
  if (!core::is_explicit(s.setup.integrator))
    throw std::invalid_argument("integrator " + core::to_string(s.setup.integrator) +
                                " is implicit; a distributed run needs an explicit integrator");
  core::check_stability(s.setup.integrator, core::max_omega(s.setup.model), s.setup.dt,
                        s.setup.allow_unstable);
  s.deployment = runtime::with_default_nodes(s.deployment, s.setup);
  plan_ = runtime::make_plan(s.setup, s.deployment);
  for (const runtime::NodePlan& n : plan_.nodes)
    for (const std::string& name : {n.spec.receive_delay_case(), n.spec.send_delay_case()})
      if (!name.empty()) runtime::find_case(s.prepared.config, name);  // throws naming it
  s.plan = &plan_;
  s.real_time = s.deployment.clock() == config::Deployment::REAL_TIME;
  for (const runtime::NodePlan& n : plan_.nodes) {
    s.nodes[n.spec.id()].plan = &n;
    s.nodes[n.spec.id()].link.set_node_id(n.spec.id());  // answered_step 0: no answer yet
  }
  const int storeys = static_cast<int>(s.setup.partition.numerical.size());
  const int actuators = static_cast<int>(s.setup.partition.actuator_storeys.size());
  s.assembly = core::StoreyAssembly(storeys);
  if (plan_.numerical_local)
    s.local_numerical = std::make_unique<core::NumericalSubstructure>(
        core::HybridPartition(s.setup.partition).numerical);
  s.drift = core::Vec::Zero(storeys);
  s.drift_velocity = core::Vec::Zero(storeys);
  s.shear = core::Vec::Zero(storeys);
  s.force = core::Vec::Zero(storeys);
  s.command = core::Vec::Zero(actuators);
  s.realised = core::Vec::Zero(actuators);
  s.measured = core::Vec::Zero(actuators);
}

Coordinator::~Coordinator() = default;

RunOutcome Coordinator::run() {
  State& s = *state_;
  const auto wall_start = Clock::now();
  RunOutcome outcome;
  if (!s.options.record.empty())
    s.record = std::make_unique<runtime::RecordWriter>(s.options.record);

  const core::HybridSetup& setup = s.setup;
  const core::GroundMotion& motion = s.prepared.motion;
  const int dofs = setup.model.dofs();
  const int actuators = static_cast<int>(setup.partition.actuator_storeys.size());
  const std::size_t steps = motion.acceleration.size();
  core::SimulationResult& result = outcome.result;
  result.dt = setup.dt;
  const auto rows = static_cast<Eigen::Index>(steps);
  result.time.assign(steps, 0.0);
  result.displacement = core::Mat::Zero(rows, dofs);
  result.velocity = core::Mat::Zero(rows, dofs);
  result.acceleration = core::Mat::Zero(rows, dofs);
  result.command = core::Mat::Zero(rows, actuators);
  result.realised = core::Mat::Zero(rows, actuators);
  result.measured_force = core::Mat::Zero(rows, actuators);

  runtime::MonotonicClock monotonic;
  runtime::PacingClock& pacing_clock = s.options.clock ? *s.options.clock : monotonic;
  runtime::Pacer pacer(pacing_clock, setup.dt);
  std::size_t completed = 1;
  bool failed = false;
  double step_wall = 0.0;

  auto write_step = [&](std::size_t k, const runtime::PaceResult& pace) {
    if (!s.record) return;
    runtime::RecordEntry entry;
    runtime::StepRecord& r = *entry.mutable_step();
    const auto row = static_cast<Eigen::Index>(k);
    r.set_step(static_cast<std::int64_t>(k));
    r.set_time(result.time[k]);
    r.set_ground_acceleration(motion.acceleration[k]);
    for (int i = 0; i < dofs; ++i) {
      r.add_displacement(result.displacement(row, i));
      r.add_velocity(result.velocity(row, i));
      r.add_acceleration(result.acceleration(row, i));
    }
    for (int a = 0; a < actuators; ++a) {
      r.add_command(result.command(row, a));
      r.add_realised(result.realised(row, a));
      r.add_measured_force(result.measured_force(row, a));
    }
    if (k > 0)
      for (auto& [id, node] : s.nodes) *r.add_links() = node.link;
    r.set_lateness(pace.lateness);
    r.set_step_wall(step_wall);
    r.set_overrun(pace.overrun);
    s.record->write(entry);
  };

  try {
    if (s.record) {
      runtime::RecordEntry entry;
      runtime::RunHeader& h = *entry.mutable_header();
      h.set_schema_version(runtime::kSchemaVersion);
      h.set_run_id(s.options.run_id);
      *h.mutable_study() = s.prepared.config;
      h.set_case_name(s.case_name);
      h.set_clock(s.real_time ? "real_time" : "lockstep");
      h.set_dt(setup.dt);
      h.set_dofs(dofs);
      h.set_actuators(actuators);
      for (auto& [id, node] : s.nodes) h.add_link_node_ids(id);
      h.set_start_realtime_ns(transport::realtime_ns());
      h.set_timestamp_clock(
          "CLOCK_REALTIME ns; round_trip uses the coordinator's clock only, one-way lags "
          "include the clock offset between hosts");
      s.record->write(entry);
    }
    s.start_up();
    s.event("all " + std::to_string(s.nodes.size()) + " nodes ready (" +
            std::string(s.real_time ? "real time" : "lockstep") + ", case " + s.case_name + ")");

    // The same sequence as core::simulate().
    auto integrator = core::make_integrator(setup.integrator, setup.model, setup.dt);
    const core::Vec mass_iota = setup.model.mass * setup.model.influence;
    core::Vec load = -mass_iota * motion.acceleration[0];
    integrator->initialize(core::Vec::Zero(dofs), core::Vec::Zero(dofs), core::Vec::Zero(dofs),
                           load);
    result.acceleration.row(0) = integrator->acceleration().transpose();
    write_step(0, {});
    s.last_heartbeat_sent = Clock::now();
    for (auto& [id, node] : s.nodes) node.last_seen = Clock::now();
    if (s.real_time) pacer.start();
    for (std::size_t k = 1; k < steps; ++k) {
      runtime::PaceResult pace;
      if (s.real_time) {
        // Take messages off the wire while waiting, so that their receive stamps (and so the
        // measured lag) are not delayed by our sleep; the last stretch is clock_nanosleep to the
        // absolute deadline.
        const std::int64_t until = pacer.deadline_ns(static_cast<std::int64_t>(k)) - kDrainMarginNs;
        for (std::int64_t now = pacing_clock.now_ns(); now < until; now = pacing_clock.now_ns())
          s.pump(std::chrono::nanoseconds(until - now));
        pace = pacer.wait(static_cast<std::int64_t>(k));
      }
      const double t = static_cast<double>(k) * setup.dt;
      result.time[k] = t;
      load = -mass_iota * motion.acceleration[k];
      s.step = static_cast<std::int64_t>(k);
      s.time = t;
      const auto step_start = Clock::now();
      integrator->step(load, s);
      step_wall = std::chrono::duration<double>(Clock::now() - step_start).count();
      const auto row = static_cast<Eigen::Index>(k);
      result.displacement.row(row) = integrator->displacement().transpose();
      result.velocity.row(row) = integrator->velocity().transpose();
      result.acceleration.row(row) = integrator->acceleration().transpose();
      result.command.row(row) = s.command.transpose();
      result.realised.row(row) = s.realised.transpose();
      result.measured_force.row(row) = s.measured.transpose();
      completed = k + 1;
      write_step(k, pace);
      const double peak = integrator->displacement().cwiseAbs().maxCoeff();
      if (!(peak <= s.options.divergence_bound)) {
        result.diverged = true;
        s.event("diverged: |u| = " + std::to_string(peak) + " m");
        break;
      }
    }
    outcome.ok = true;
    outcome.status = result.diverged ? "diverged" : "completed";
  } catch (const RunAborted& e) {
    failed = true;
    outcome.status = e.what();
    outcome.failed_node = e.node;
  } catch (const std::exception& e) {
    // Transport or record failures: still hold the actuators and close the record.
    failed = true;
    outcome.status = std::string("internal error: ") + e.what();
  }
  if (failed) {
    spdlog::error("run {} stopped at step {}: {}", s.options.run_id, s.step, outcome.status);
    for (auto& [id, node] : s.nodes) {
      if (node.plan->spec.kind() != config::NodeSpec::ACTUATOR_EMULATOR) continue;
      runtime::Hold hold;
      hold.set_reason(outcome.status);
      s.send(id, runtime::HOLD, s.step, hold);
    }
    s.event("HOLD sent to the actuator emulators: " + outcome.status);
  }
  runtime::Stop stop;
  stop.set_reason(outcome.status);
  s.send(transport::kBroadcastId, runtime::STOP, s.step, stop);

  result.truncate(completed);

  s.rejected.fill(outcome.counters);
  outcome.counters.set_overruns(pacer.overruns());
  outcome.counters.set_late_feedback(s.late_feedback);
  outcome.counters.set_steps(completed - 1);
  outcome.max_lateness = pacer.max_lateness();
  for (auto& [id, node] : s.nodes) {
    LinkLagStats stats;
    stats.node_id = id;
    stats.label = node.plan->label();
    stats.round_trip = runtime::summarize(node.round_trips);
    stats.injected = runtime::summarize(node.injected);
    outcome.links.push_back(stats);
  }
  outcome.wall_seconds = seconds_since(wall_start);
  if (s.record) {
    runtime::RecordEntry entry;
    runtime::RunFooter& f = *entry.mutable_footer();
    f.set_ok(outcome.ok);
    f.set_status(outcome.status);
    f.set_failed_node(outcome.failed_node);
    *f.mutable_counters() = outcome.counters;
    f.set_diverged(result.diverged);
    f.set_wall_seconds(outcome.wall_seconds);
    s.record->write(entry);
  }
  return outcome;
}

}  // namespace rths::coordinator
