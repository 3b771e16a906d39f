#include "coordinator/coordinator.h"

#include <spdlog/spdlog.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>

#include "coordinator/command_limits.h"
#include "coordinator/deadline_verdict.h"
#include "coordinator/feedback_intake.h"
#include "core/simulation.h"
#include "runtime/measurements.h"
#include "runtime/process.h"
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

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

struct Coordinator::State : core::HybridEvaluator, core::StepHooks {
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
    std::int64_t last_answer = 0;  // step of the newest answer taken from the intake
    std::uint64_t answers = 0;     // answers taken so far
    std::uint64_t answers_before_step = 0;
    int missed_streak = 0;         // real time: consecutive steps without a fresh answer
    int late_streak = 0;           // real time: consecutive steps on an older answer
    bool awaited = true;           // awaits_answers_of(its spec)
    std::uint64_t servo_ticks = 0, servo_overruns = 0;  // as of its last heartbeat
  };
  std::map<int, Node> nodes;
  // The nodes' feedback, filled by the transport's receive thread (or by pump() on a transport
  // without one) and read wait-free by the loop.
  std::unique_ptr<FeedbackIntake> intake;
  runtime::RejectCounters rejected;  // everything but feedback (the intake counts those)
  std::uint64_t late_feedback = 0, worst_late_streak = 0;
  // The links' lag as the record's reader counts it (runtime/measurements.h), from the same samples.
  runtime::LinkLagAccumulator lags;
  std::unique_ptr<CommandLimits> limits;  // checked before each command leaves

  // Evaluator state (sized once).
  core::StoreyAssembly assembly{1};
  std::unique_ptr<core::NumericalSubstructure> local_numerical;
  core::Vec drift, drift_velocity, shear, force, command_drift, realised_drift, measured;
  std::int64_t step = 0;
  double time = 0.0;
  runtime::Command command_message;
  std::unique_ptr<runtime::AsyncRecordWriter> record;
  // Reused every step so that, after the first steps, building an entry allocates nothing.
  runtime::RecordEntry step_entry;
  runtime::StepRecord step_record;

  // Off the loop (header, footer): waits for room rather than drop.
  void append_waiting(const runtime::RecordEntry& entry) {
    while (!record->append(entry)) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  Clock::time_point last_heartbeat_sent;

  State(core::PreparedStudy p, transport::Endpoint& e, CoordinatorOptions o)
      : prepared(std::move(p)), endpoint(e), options(std::move(o)) {}

  std::string label(int id) const {
    const auto it = nodes.find(id);
    return it != nodes.end() ? it->second.plan->label() : "node " + std::to_string(id);
  }

  void send(int node_id, runtime::MessageKind kind, std::int64_t at_step,
            const google::protobuf::MessageLite& payload) {
    runtime::pack_into(outgoing, options.run_id, node_id, kind, at_step, payload);
    endpoint.send(outgoing);
  }
  transport::Message outgoing;  // reused: no allocation per command once warm

  void event(const std::string& what) {
    spdlog::info("step {}: {}", step, what);
    if (!record) return;
    runtime::RecordEntry entry;
    entry.mutable_event()->set_step(step);
    entry.mutable_event()->set_what(what);
    entry.mutable_event()->set_realtime_ns(transport::realtime_ns());
    record->append(entry);  // a full queue drops it and counts it, as for steps
  }

  // Takes one message off the transport and applies it if valid. False on timeout.
  bool pump(std::chrono::nanoseconds timeout) {
    auto message = endpoint.receive(timeout);
    if (!message) return false;
    if (message->kind == runtime::FEEDBACK) {
      intake->offer(*message);
      return true;
    }
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
      case runtime::HOLD: {
        // An emulator held on its own (its watchdog or limits): the test cannot go on.
        runtime::Hold hold;
        if (!runtime::unpack(*message, hold)) {
          rejected.count(Verdict::kGarbage);
          return true;
        }
        throw RunAborted("held on its own at its step " + std::to_string(message->step) + ": " +
                             hold.reason(),
                         node.plan->label());
      }
      case runtime::HEARTBEAT: {
        node.last_seen = Clock::now();
        runtime::Heartbeat heartbeat;
        if (runtime::unpack(*message, heartbeat)) {
          node.servo_ticks = heartbeat.servo_ticks();
          node.servo_overruns = heartbeat.servo_overruns();
        }
        return true;
      }
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
  // Whether the loop waits for the node's answer to each step: always in lockstep; in real time
  // unless the node's link injects a round trip (receive_lag + send_lag one-way delays; jitter
  // has zero mean) at least as long as the wait, so its answer cannot come in time and waiting
  // for it would only eat half of every period (and turn a small hiccup into an overrun).
  bool awaits_answers_of(const config::NodeSpec& spec) const {
    if (!real_time) return true;
    const double injected = spec.receive_lag().one_way_delay() + spec.send_lag().one_way_delay();
    return injected < runtime::feedback_wait_fraction(deployment) * setup.dt;
  }

  // Takes each node's newest feedback from the intake, if new since the last take.
  void absorb() {
    for (auto& [id, node] : nodes) {
      const ArrivedFeedback* arrived = intake->take(id);
      if (!arrived) continue;
      node.last_seen = Clock::now();
      node.last_answer = arrived->answered_step;
      node.answers = arrived->answers;
    }
  }

  const core::Vec& trial(const core::Vec& u, const core::Vec& v, core::Mat* tangent) override {
    if (tangent)
      throw std::invalid_argument("the distributed runtime needs an explicit integrator");
    if (auto violation = limits->check_state(u, v)) throw RunAborted(*violation, "");
    assembly.drifts(u, drift);
    assembly.drifts(v, drift_velocity);
    if (auto violation = limits->check_rate(drift)) throw RunAborted(*violation, "");
    for (auto& [id, node] : nodes) {
      command_message.Clear();
      command_message.set_time(time);
      for (int s : node.plan->storeys) {
        command_message.add_drift(drift[s]);
        command_message.add_drift_velocity(drift_velocity[s]);
      }
      send(id, runtime::COMMAND, step, command_message);
    }
    commands_written = Clock::now();
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
        command_drift[a] = drift[s];
        realised_drift[a] = realised_of(node, i);
        measured[a] = force_of(node, i);
      }
    }
    core::assemble_storey_forces(assembly, storeys, measured, shear, force);
    return force;
  }
  void set_time(double t) override { time = t; }
  const core::Vec& command() const override { return command_drift; }
  const core::Vec& realised() const override { return realised_drift; }
  const core::Vec& measured_force() const override { return measured; }
  int actuators() const override { return static_cast<int>(measured.size()); }

  // Before a node's first answer (real time, lag longer than the wait) the specimen is at rest.
  double force_of(const Node& node, std::size_t i) {
    const runtime::Feedback& f = intake->latest(node.plan->spec.id()).feedback;
    const int index = static_cast<int>(i);
    return index < f.force_size() ? f.force(index) : 0.0;
  }
  double realised_of(const Node& node, std::size_t i) {
    const runtime::Feedback& f = intake->latest(node.plan->spec.id()).feedback;
    const int index = static_cast<int>(i);
    return index < f.realised_size() ? f.realised(index) : 0.0;
  }
  const runtime::LinkSample& link_of(int id) { return intake->latest(id).link; }

  void commit() override {
    if (local_numerical) local_numerical->commit();
  }
  bool repeatable() const override { return false; }

  // ---- StepHooks: pacing before a step, record after it ----
  runtime::PacingClock* pacing_clock = nullptr;  // set by run()
  runtime::Pacer* pacer = nullptr;
  runtime::PaceResult pace;
  Clock::time_point step_start, commands_written;
  std::int64_t step_start_realtime_ns = 0;

  void before_step(std::size_t k) override {
    pace = {};
    // One timed wait per period, the pacer's: feedback is stamped and boxed on the receive thread
    // meanwhile, and other messages wait in the transport's queue (stamped on arrival). A second
    // timed wait here (draining until shortly before the deadline, as before) turned every late
    // wake-up of it into an overrun.
    if (real_time) {
      pace = pacer->wait(static_cast<std::int64_t>(k));
      // What queued during the wait (an emulator's HOLD stops the run before the next command).
      while (pump(std::chrono::nanoseconds::zero())) {
      }
    }
    step = static_cast<std::int64_t>(k);
    intake->await_step(step);
    step_start = Clock::now();
    step_start_realtime_ns = transport::realtime_ns();
  }

  bool after_step(std::size_t k, const core::SimulationResult& result) override {
    const double step_wall = k == 0 ? 0.0 : seconds_since(step_start);
    write_step(k, result, step_wall);
    if (k > 0)
      for (auto& [id, node] : nodes) lags.add(result.time[k], link_of(id));
    if (k == 0) {
      last_heartbeat_sent = Clock::now();
      for (auto& [id, node] : nodes) node.last_seen = Clock::now();
      if (real_time) pacer->start();
    }
    return true;
  }

  // mlockall and the loop thread's CPU, as the deployment asks. Refusals are logged events, not
  // failures: an unprivileged lab machine still runs, and the record says it was not locked.
  void prepare_real_time_thread() {
    if (deployment.lock_memory()) {
      if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
        event(std::string("mlockall refused (") + std::strerror(errno) + "); memory not locked");
      else
        event("memory locked (mlockall)");
    }
    if (deployment.pin_loop()) {
      // The CPU is the loop's alone: a receive thread woken on it would preempt the loop between
      // its commands (bench: wake-up to command written 31 -> 18 us median at 1024 Hz).
      try {
        runtime::isolate_calling_thread_on_cpu(deployment.loop_cpu());
        event("loop thread alone on CPU " + std::to_string(deployment.loop_cpu()) +
              " (the process's other threads moved off it)");
      } catch (const std::runtime_error& e) {
        event(std::string("loop thread not isolated: ") + e.what());
      }
    }
  }

  void write_header() {
    if (!record) return;
    runtime::RecordEntry entry;
    runtime::RunHeader& h = *entry.mutable_header();
    h.set_schema_version(runtime::kSchemaVersion);
    h.set_run_id(options.run_id);
    *h.mutable_study() = prepared.config;
    h.set_case_name(case_name);
    h.set_clock(real_time ? "real_time" : "lockstep");
    h.set_dt(setup.dt);
    h.set_dofs(setup.model.dofs());
    h.set_actuators(static_cast<int>(setup.partition.actuator_storeys.size()));
    for (auto& [id, node] : nodes) h.add_link_node_ids(id);
    h.set_start_realtime_ns(transport::realtime_ns());
    h.set_timestamp_clock(
        "CLOCK_REALTIME ns; round_trip uses the coordinator's clock only, one-way lags "
        "include the clock offset between hosts");
    append_waiting(entry);
  }

  void write_step(std::size_t k, const core::SimulationResult& result, double step_wall) {
    if (!record) return;
    runtime::StepRecord& r = step_record;
    r.Clear();  // keeps the repeated fields' storage
    const auto row = static_cast<Eigen::Index>(k);
    r.set_step(static_cast<std::int64_t>(k));
    r.set_time(result.time[k]);
    r.set_ground_acceleration(prepared.motion.acceleration[k]);
    for (int i = 0; i < result.displacement.cols(); ++i) {
      r.add_displacement(result.displacement(row, i));
      r.add_velocity(result.velocity(row, i));
      r.add_acceleration(result.acceleration(row, i));
    }
    for (int a = 0; a < result.command.cols(); ++a) {
      r.add_command(result.command(row, a));
      r.add_realised(result.realised(row, a));
      r.add_measured_force(result.measured_force(row, a));
    }
    if (k > 0)
      for (auto& [id, node] : nodes) *r.add_links() = link_of(id);
    r.set_lateness(pace.lateness);
    r.set_step_wall(step_wall);
    r.set_command_latency(
        k == 0 ? 0.0 : std::chrono::duration<double>(commands_written - step_start).count());
    r.set_overrun(pace.overrun);
    r.set_start_realtime_ns(k == 0 ? 0 : step_start_realtime_ns);
    step_entry.unsafe_arena_set_allocated_step(&step_record);
    record->append(step_entry);
    step_entry.unsafe_arena_release_step();
  }

  void collect() {
    if (real_time) {
      // Wait part of the step for this step's answers, then go with the newest available.
      const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(
                                                runtime::feedback_wait_fraction(deployment) *
                                                setup.dt));
      for (;;) {
        absorb();
        bool all = true;
        for (auto& [id, node] : nodes) all = all && (!node.awaited || node.last_answer == step);
        if (all) break;
        const auto left = until - Clock::now();
        if (left <= Clock::duration::zero()) break;
        pump(left);
      }
      while (pump(std::chrono::nanoseconds::zero())) {
      }
      absorb();
      const int max_missed = runtime::max_missed_answers(deployment);
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
        node.answers_before_step = node.answers;
        node.missed_streak = fresh || node.answers == 0 ? 0 : node.missed_streak + 1;
        if (node.missed_streak >= max_missed)
          throw RunAborted("no answer for " + std::to_string(node.missed_streak) +
                               " consecutive steps (steps " +
                               std::to_string(step - node.missed_streak + 1) + " to " +
                               std::to_string(step) + "; its newest answers step " +
                               std::to_string(node.last_answer) + ")",
                           node.plan->label());
      }
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
  runtime::check_node_stages(plan_, s.setup.dt, s.prepared.base_dir);
  s.plan = &plan_;
  s.real_time = s.deployment.clock() == config::Deployment::REAL_TIME;
  const std::size_t steps = s.prepared.motion.acceleration.size();
  std::vector<IntakeNode> intake_nodes;
  for (const runtime::NodePlan& n : plan_.nodes) {
    State::Node& node = s.nodes[n.spec.id()];
    node.plan = &n;
    node.awaited = s.awaits_answers_of(n.spec);
    s.lags.reserve(n.spec.id(), steps);  // no growth on the loop
    intake_nodes.push_back({n.spec.id(), static_cast<int>(n.storeys.size()),
                            n.spec.kind() == config::NodeSpec::ACTUATOR_EMULATOR, node.awaited});
  }
  s.intake = std::make_unique<FeedbackIntake>(s.options.run_id, intake_nodes);
  const int storeys = static_cast<int>(s.setup.partition.numerical.size());
  const int actuators = static_cast<int>(s.setup.partition.actuator_storeys.size());
  s.assembly = core::StoreyAssembly(storeys);
  if (plan_.numerical_local)
    s.local_numerical = std::make_unique<core::NumericalSubstructure>(
        core::HybridPartition(s.setup.partition).numerical);
  s.drift = core::Vec::Zero(storeys);
  s.limits = std::make_unique<CommandLimits>(s.deployment.limits(),
                                             s.setup.partition.actuator_storeys, storeys);
  s.drift_velocity = core::Vec::Zero(storeys);
  s.shear = core::Vec::Zero(storeys);
  s.force = core::Vec::Zero(storeys);
  s.command_drift = core::Vec::Zero(actuators);
  s.realised_drift = core::Vec::Zero(actuators);
  s.measured = core::Vec::Zero(actuators);
}

Coordinator::~Coordinator() = default;

RunOutcome Coordinator::run() {
  State& s = *state_;
  const auto wall_start = Clock::now();
  RunOutcome outcome;
  if (!s.options.record.empty())
    s.record = std::make_unique<runtime::AsyncRecordWriter>(s.options.record);

  runtime::MonotonicClock monotonic;
  runtime::PacingClock& pacing_clock = s.options.clock ? *s.options.clock : monotonic;
  runtime::Pacer pacer(pacing_clock, s.setup.dt, runtime::wait_policy(s.deployment));
  s.pacing_clock = &pacing_clock;
  s.pacer = &pacer;
  core::SimulationResult& result = outcome.result;
  bool failed = false;

  try {
    s.write_header();
    s.start_up();
    s.event("all " + std::to_string(s.nodes.size()) + " nodes ready (" +
            std::string(s.real_time ? "real time" : "lockstep") + ", case " + s.case_name + ")");
    if (s.real_time) s.prepare_real_time_thread();
    for (const auto& [id, node] : s.nodes)
      if (!node.awaited)
        s.event("not waiting for the answers of " + node.plan->label() + ": its link injects a " +
                std::to_string(1e3 * (node.plan->spec.receive_lag().one_way_delay() +
                                      node.plan->spec.send_lag().one_way_delay())) +
                " ms round trip, longer than the loop's wait of " +
                std::to_string(1e3 * runtime::feedback_wait_fraction(s.deployment) * s.setup.dt) +
                " ms; each step uses its newest answer");
    core::SimulationOptions loop_options;
    loop_options.divergence_bound = s.options.divergence_bound;
    {
      // Feedback is judged and boxed on the transport's receive thread; the loop is woken once
      // a step's answers are all in. Removed (waiting out a running call) before the loop ends.
      s.endpoint.set_inline_handler([&s](const transport::Message& m) {
        if (m.kind != runtime::FEEDBACK) return false;
        if (s.intake->offer(m)) s.endpoint.interrupt();
        return true;
      });
      struct RemoveHandler {
        transport::Endpoint& endpoint;
        ~RemoveHandler() { endpoint.set_inline_handler(nullptr); }
      } remove_handler{s.endpoint};
      core::run_steps(s.setup, s.prepared.motion, s, s, loop_options, result);
    }
    if (result.diverged)
      s.event("diverged: |u| = " +
              std::to_string(result.displacement.bottomRows(1).cwiseAbs().maxCoeff()) + " m");
    outcome.ok = !result.diverged;
    outcome.status = result.diverged ? "diverged" : "completed";
    const double tolerance = runtime::max_overrun_fraction(s.deployment);
    std::optional<std::string> misses;
    if (s.real_time && !result.diverged)
      misses = loop_deadline_misses(pacer.overruns(), pacer.worst_overrun_streak(),
                                    result.steps() > 0 ? result.steps() - 1 : 0, tolerance);
    for (const auto& [id, node] : s.nodes)
      if (outcome.ok && !misses)
        misses = servo_deadline_misses(node.plan->label(), node.servo_overruns, node.servo_ticks,
                                       tolerance);
    if (misses) {
      outcome.ok = false;
      outcome.status = *misses;
      s.event(outcome.status);
    }
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
      // A node that never announced runs nothing of this run (and has no addressed topic yet).
      if (node.plan->spec.kind() != config::NodeSpec::ACTUATOR_EMULATOR || !node.announced) continue;
      runtime::Hold hold;
      hold.set_reason(outcome.status);
      s.send(id, runtime::HOLD, s.step, hold);
    }
    s.event("HOLD sent to the actuator emulators: " + outcome.status);
  }
  // Addressed to each node that announced, after its HOLD on the same topic, so the STOP cannot
  // overtake the HOLD (DDS orders per topic only: a broadcast STOP did, in 1 of 23 fault trials).
  // A node that never announced was never assigned, and an unassigned node ignores all but ASSIGN.
  runtime::Stop stop;
  stop.set_reason(outcome.status);
  for (auto& [id, node] : s.nodes)
    if (node.announced) s.send(id, runtime::STOP, s.step, stop);

  const std::size_t completed = result.steps();
  runtime::RejectCounters rejected = s.rejected;
  rejected.add(s.intake->rejected());
  rejected.fill(outcome.counters);
  outcome.counters.set_overruns(pacer.overruns());
  outcome.counters.set_late_feedback(s.late_feedback);
  outcome.counters.set_worst_overrun_streak(pacer.worst_overrun_streak());
  outcome.counters.set_worst_late_streak(s.worst_late_streak);
  outcome.counters.set_steps(completed > 0 ? completed - 1 : 0);
  for (const auto& [id, node] : s.nodes) {
    outcome.counters.set_servo_ticks(outcome.counters.servo_ticks() + node.servo_ticks);
    outcome.counters.set_servo_overruns(outcome.counters.servo_overruns() + node.servo_overruns);
  }
  outcome.max_lateness = pacer.max_lateness();
  for (auto& [id, node] : s.nodes) {
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
  outcome.wall_seconds = seconds_since(wall_start);
  if (s.record && s.record->dropped() > 0) {
    // A gap in the record is lost data: the run did not do what it was for.
    outcome.ok = false;
    outcome.status += "; the run record lost " + std::to_string(s.record->dropped()) +
                      " entries (its writer fell more than " +
                      std::to_string(s.record->capacity()) + " entries behind)";
  }
  if (s.record) {
    runtime::RecordEntry entry;
    runtime::RunFooter& f = *entry.mutable_footer();
    f.set_ok(outcome.ok);
    f.set_status(outcome.status);
    f.set_failed_node(outcome.failed_node);
    *f.mutable_counters() = outcome.counters;
    f.set_diverged(result.diverged);
    f.set_wall_seconds(outcome.wall_seconds);
    s.append_waiting(entry);
    s.record->close();  // throws naming the file when a write failed
  }
  s.pacer = nullptr;
  s.pacing_clock = nullptr;
  return outcome;
}

}  // namespace rths::coordinator
