#pragma once
// The coordinator's configuration (RunConfiguration: fixed once constructed) and its run state
// (RunState's own members), shared by the files that implement them (internal to
// rths_coordinator; the contract is in coordinator.h):
//   exchange.cpp     messages with the nodes (start-up, liveliness) and the step's exchange
//                    (the restoring-force evaluator: commands out, answers in)
//   step_hooks.cpp   pacing before a step, the real-time thread, the record after it
//   coordinator.cpp  construction from the study and the run's lifecycle and outcome

#include <spdlog/spdlog.h>

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "coordinator/answer_age.h"
#include "coordinator/answer_wait.h"
#include "coordinator/command_limits.h"
#include "coordinator/feedback_intake.h"
#include "coordinator/run_types.h"
#include "core/simulation.h"
#include "runtime/node/schema.h"
#include "runtime/node/validation.h"
#include "runtime/record/measurements.h"
#include "runtime/rt/fifo.h"

namespace rths::coordinator {

using Clock = std::chrono::steady_clock;

// After the STOPs, how long the coordinator waits for every node's last heartbeat (what it
// rejected, by cause); a node that does not send it in time is reported as of its last one.
inline constexpr auto kFinalReportWait = std::chrono::milliseconds(1000);

inline double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// What the run is: the study, the case and the deployment, settled by the constructor and never
// changed by the run (the run's state is RunState's own members).
struct RunConfiguration {
  study::PreparedStudy prepared;
  core::HybridSetup setup;
  std::string case_name;
  CoordinatorOptions options;
  config::Deployment deployment;
  bool real_time = false;
};

struct RunState : RunConfiguration, core::HybridEvaluator, core::StepHooks {
  transport::Endpoint& endpoint;

  // Per node.
  struct Node {
    const runtime::NodePlan* plan;
    bool announced = false, ready = false;
    Clock::time_point last_seen;
    std::int64_t last_answer = 0;  // step of the newest answer taken from the intake
    std::uint64_t answers = 0;     // answers taken so far
    std::uint64_t answers_before_step = 0;
    int missed_streak = 0;  // real time: consecutive steps without a fresh answer
    int late_streak = 0;    // real time: consecutive steps on an older answer
    std::uint64_t fresh_steps = 0, judged_steps = 0;  // real time: for answer_shortfall
    bool awaited = true;  // the loop waits for its answers: awaits_answers_of(its spec), then
                          // in real time as wait_judge decides
    std::optional<AnswerWait> wait_judge;  // real time, for a node awaited at the start
    std::uint64_t servo_ticks = 0, servo_overruns = 0;  // as of its last heartbeat
    std::uint64_t writer = 0;   // its announcement's writer: only it may speak as this node
    runtime::Counters rejects;  // what the node rejected, by cause, as of its last heartbeat
    bool final_report = false;  // that heartbeat was its last (sent on STOP)
    runtime::ControllerReport controller;  // a CONTROLLER node's link, as of its last heartbeat
    std::optional<AnswerWindow> window;    // real time: the oldest answer a step may apply
    AnswerAgeTally ages;                   // real time: each step's applied answer's age
  };
  std::map<int, Node> nodes;
  // The nodes' feedback, filled by the transport's receive thread (or by pump() on a transport
  // without one) and read wait-free by the loop.
  std::unique_ptr<FeedbackIntake> intake;
  runtime::RejectCounters rejected;  // everything but feedback (the intake counts those)
  std::uint64_t late_feedback = 0, worst_late_streak = 0;
  // The links' lag as the record's reader counts it (runtime/record/measurements.h), from the same
  // samples.
  runtime::LinkLagAccumulator lags;
  std::unique_ptr<CommandLimits> limits;  // checked before each command leaves

  // Evaluator state (sized once).
  core::StoreyAssembly assembly{1};
  std::unique_ptr<core::NumericalSubstructure> local_numerical;
  core::Vec drift, drift_velocity, shear, force, command_drift, realised_drift, measured;
  // The case's force predictors (none: empty), the force they hand the integrator, the command
  // rate and the answer step each reads, and each one's error (N) of the step.
  core::PredictorSet predictors;
  core::Vec used_force, command_rate, prediction_error_;
  std::vector<long> answer_steps;
  std::string hold_;
  std::int64_t step = 0;
  double time = 0.0;
  runtime::Command command_message;
  std::unique_ptr<runtime::AsyncRecordWriter> record;
  // Reused every step so that, after the first steps, building an entry allocates nothing.
  runtime::RecordEntry step_entry;
  runtime::StepRecord step_record;
  // The header as written first; written again just before the footer (the record writer also
  // copies it before the first step and every kHeaderRepeatSteps steps), so a record whose first
  // copy is damaged still has one (readers take the first copy that reads).
  runtime::RecordEntry header_entry;

  // Off the loop (header, footer): waits for room rather than drop.
  void append_waiting(const runtime::RecordEntry& entry) {
    while (!record->append(entry)) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  Clock::time_point last_heartbeat_sent;

  RunState(study::PreparedStudy p, transport::Endpoint& e, CoordinatorOptions o)
      : RunConfiguration{std::move(p), {}, {}, std::move(o), {}, false}, endpoint(e) {}

  void send(int node_id, runtime::MessageKind kind, std::int64_t at_step,
            const google::protobuf::MessageLite& payload) {
    runtime::pack_into(outgoing, options.run_id, node_id, kind, at_step, payload);
    outgoing.sent_ns = transport::realtime_ns();
    endpoint.send(outgoing);
  }
  transport::Message outgoing;  // reused: no allocation per command once warm

  // Logs what happened and appends it to the record as an event (a full ring drops and counts it).
  void event(const std::string& what);
  // The control room's presses (options.control): each recorded; an allowed HOLD sent to its
  // nodes, then the run held (hold_run); an allowed STOP throws RunAborted naming who.
  void apply_presses();
  // The run held from the view (`why`: who held it), at `step`: no further step is integrated (the
  // loop cannot integrate past a held actuator), so no command leaves and every other lab's
  // actuators stay at their last one (a real-time emulator's watchdog then holds it where it
  // stands). Messages, liveliness and the heartbeat go on; a node's command-watchdog HOLD is
  // recorded, not a fault; any other HOLD of a node's own is its fault. Leaves only by RunAborted:
  // the director's STOP (or the stop request) or a node's fault, naming the node.
  [[noreturn]] void hold_run(const std::string& why);
  std::string held_from_view;  // while the run is held: why (hold_run's `why`)

  // ---- Messages (exchange.cpp) ----
  // Takes one message off the transport and applies it if valid. False on timeout.
  bool pump(std::chrono::nanoseconds timeout);
  // A message from `node` that passed the envelope and sender checks.
  void apply(const transport::Message& message, Node& node);
  void on_announce(const transport::Message& message, const runtime::Announce& announce,
                   Node& node);

  void send_assign(const Node& node);
  // Throws RunAborted for a node silent beyond the liveliness timeout; sends the heartbeat when
  // it is due.
  void check_liveliness();
  void send_heartbeat_when_due();
  // Until every node is READY (start_timeout), naming each that never announced or became ready.
  void start_up();

  // ---- RestoringEvaluator: one exchange per step (exchange.cpp) ----
  // Whether the loop waits for the node's answer to each step: always in lockstep; in real time
  // unless the node's link injects a round trip (receive_lag + send_lag one-way delays; jitter
  // has zero mean) at least as long as the wait, so its answer cannot come in time and waiting
  // for it would only eat half of every period (and turn a small hiccup into an overrun).
  bool awaits_answers_of(const config::NodeSpec& spec) const;
  // s: the round trip the node's link injects (one-way delays both ways; jitter has zero mean).
  static double injected_round_trip(const config::NodeSpec& spec);
  // s: how long a real-time step waits for its answers (feedback_wait_fraction x dt).
  double answer_wait() const;

  // Takes each node's newest feedback from the intake, if new since the last take, and gives a
  // new answer's round trip to the node's wait_judge. Throws RunAborted, naming the node, once
  // the intake raised an integrity fault.
  void absorb();
  // Applies wait_judge's switch: the loop and the intake stop (or start again) waiting for the
  // node's answers; an event says why. The event allocates and logs on the loop thread, which
  // is why switches are rare (AnswerWait's back-off: a handful per run at most).
  void switch_answer_wait(int id, Node& node, const AnswerWait::Switch& change);

  const core::Vec& trial(const core::Vec& u, const core::Vec& v, core::Mat* tangent) override;
  void set_time(double t) override { time = t; }
  const core::Vec& command() const override { return command_drift; }
  const core::Vec& realised() const override { return realised_drift; }
  const core::Vec& measured_force() const override { return measured; }
  int actuators() const override { return static_cast<int>(measured.size()); }
  const core::Vec& prediction_error() const override { return prediction_error_; }
  const std::string& hold() const override { return hold_; }

  // Before a node's first answer (real time, lag longer than the wait) the specimen is at rest.
  double force_of(const Node& node, std::size_t i);
  double realised_of(const Node& node, std::size_t i);
  const runtime::LinkSample& link_of(int id) { return intake->latest(id).link; }

  void commit() override {
    if (local_numerical) local_numerical->commit();
  }
  bool repeatable() const override { return false; }

  // Waits for the step's answers (lockstep: all, within step_timeout; real time: the awaited
  // ones, within feedback_wait_fraction of the step), takes what queued, judges missed answers.
  void collect();
  // Real time, after collect's wait: counts the node's fresh and late steps, then stops the run
  // (RunAborted naming the node) when it gave no fresh answer for max_missed_answers steps, or
  // when its newest answer is older than its AnswerWindow: no answer that old is ever applied.
  void judge_answers(int max_missed);
  void judge_answer_age(Node& node);

  // ---- StepHooks: pacing before a step, record after it (step_hooks.cpp) ----
  runtime::Pacer* pacer = nullptr;
  runtime::PaceResult pace;
  Clock::time_point step_start, commands_written;
  std::int64_t step_start_realtime_ns = 0;
  // The loop thread's CPU time (CLOCK_THREAD_CPUTIME_ID) over each step's work, the span
  // step_wall times: what the step itself ran, never the time it waited for a CPU or slept for
  // answers, so a machine's load barely moves it while code that burns CPU in the step does.
  // s, one per step after the first; reserved for the run's steps (no growth on the loop).
  std::int64_t step_cpu_start = 0;  // ns, runtime::thread_cpu_ns
  std::vector<double> step_cpu;

  void before_step(std::size_t k) override;
  bool after_step(std::size_t k, const core::SimulationResult& result) override;

  // mlockall, the loop thread's CPU and SCHED_FIFO for the loop and the DDS receive threads
  // (realtime_priority), as the deployment asks. Refusals are logged events, not failures: an
  // unprivileged lab machine still runs, and the record says it was not locked or raised.
  void prepare_real_time_thread();
  std::optional<runtime::FifoThreads> fifo;  // raised for the run, put back when it ends

  void write_header();
  void write_step(std::size_t k, const core::SimulationResult& result, double step_wall);
  // After each step: a record whose writer failed (disk full, I/O error) or fell behind beyond
  // its ring stops the run (RunAborted naming the file and the reason): nothing would be kept.
  // Detected within a step or two of the failed write (the writer flushes whenever its ring runs
  // empty, and this runs every step).
  void check_record();
  bool record_failed = false;  // check_record() stopped the run
};

}  // namespace rths::coordinator
