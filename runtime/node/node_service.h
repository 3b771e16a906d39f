#pragma once
// What every node does with messages, independent of transport and of its kind:
//   before assignment   announce itself; accept the first ASSIGN (of the expected run, if given),
//                       build its part (configure) and answer READY (or READY with an error).
//   after assignment    COMMAND of the next step (lockstep: exactly last + 1; real time: newer,
//                       at most a liveliness timeout of steps ahead) -> compute -> FEEDBACK echoing
//                       the command's stamp; HOLD -> freeze (further commands ignored); STOP ->
//                       stopped(), answered by the node's last heartbeat (final, with its rejects
//                       by cause); a command the node refuses (refusal(): an emulator's rate limit)
//                       -> it holds on its own and answers HOLD with the reason instead of
//                       FEEDBACK. foreign-run, garbage, duplicate and stale messages are counted,
//                       never applied. Each heartbeat also carries, as rejected_by_cause's
//                       unauthenticated, what the node's transport dropped unread for want of a
//                       valid MAC (set_unauthenticated_source), so the coordinator's record
//                       shows it.
//   trust               ASSIGN, COMMAND, HOLD and STOP count only on the node's own command
//                       topic (never the broadcast) and, after the first accepted ASSIGN, only
//                       from the writer that sent it (transport::Message::writer; 0 = unknown,
//                       not checked); anything else is counted not entitled. An empty run id is
//                       never this run's. A command whose time, drifts or drift velocities are not
//                       finite, or beyond twice the run's max_displacement / max_velocity (a
//                       storey drift spans two DOFs, each within the limit), is counted out of
//                       range and not acted on.
//   node delay stages   the spec's receive_delay / send_delay stages (simulated time) act on
//                       each received drift before compute() and on each force after it; the
//                       receive chains' sensors (core::DelayStage sensor_error, measure_force:
//                       a sensor_drift or a tracking loop's load cell) act on the answer's
//                       realised drift and force, as a case's stages do in process.
//   streaming           real time with a servo loop faster than the integrator (servo_period() > 0):
//                       a COMMAND only loads the servo (load()); the node loop calls servo_tick()
//                       every servo period, which steps the servo (tick()) and returns a FEEDBACK
//                       for the newest command, stamped with its servo sample. Held, stopped or
//                       before the first command: no tick runs and nothing is sent.
//   asynchronous        a node whose answers come from a source of their own (answer_source()
//                       non-null after configure(): runtime/node/answer_source.h; a
//                       controller's UDP link): a COMMAND only dispatches to it (nothing waits),
//                       and the node loop's answer thread calls await_answers(deadline) without
//                       the loop's lock, then take_answers(send) with it, which sends a FEEDBACK
//                       for each answer, echoing the envelope of the step it answers (kept for
//                       kEnvelopes steps), or the HOLD a fault makes. Held or stopped, answers
//                       are no longer forwarded and the source comes to rest on that thread; the
//                       final heartbeat then waits until it has (final_heartbeat_due()).
//                       Simulated-time stages (receive_delay, send_delay) and send_lag are
//                       refused: they act per command, and such a node answers when its source
//                       does.
//   real time           handle(message, send), servo_tick() and take_answers() allocate nothing
//                       per command once warm: each reply is packed into a buffer the service
//                       keeps (a HOLD, a refusal and a reject's log line aside).
// Subclasses (substructure node, actuator emulator, controller node) supply configure() and
// either compute() or an answer source.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/delay.h"
#include "rths/proto/runtime.pb.h"
#include "runtime/node/answer_source.h"
#include "runtime/node/setup_progress.h"
#include "runtime/node/validation.h"
#include "transport/in_process.h"

namespace rths::runtime {

class NodeService : public transport::NodeHandler {
 public:
  // `expected_run_id` empty: adopt the run id of the first ASSIGN addressed to this node.
  NodeService(std::int32_t node_id, config::NodeSpec::Kind kind, std::string expected_run_id);
  std::vector<transport::Message> start() override;
  std::vector<transport::Message> handle(const transport::Message& message) override;
  // Where the service's replies go, each valid only during the call.
  using Send = std::function<void(const transport::Message&)>;
  // handle() with each reply passed to `send` as it is made: the real-time path (see "real
  // time"); the handler's vector copies them.
  void handle(const transport::Message& message, const Send& send);

  transport::Message announce() const;
  transport::Message heartbeat() const;
  // Freezes the node (as a HOLD from the coordinator does) and returns the HOLD message that tells
  // the coordinator why. Used by the node's own watchdog and limits. Idempotent: a second call
  // returns nullopt.
  std::optional<transport::Message> hold_on_own(const std::string& reason);
  // Streaming only: one servo period. nullopt when not streaming, held, stopped or before the
  // first command. Counts `overrun` (the period started past its deadline) for the heartbeat.
  std::optional<transport::Message> servo_tick(bool overrun);
  bool streaming() const { return streaming_; }
  double streaming_period() const { return streaming_ ? stream_period_ : 0.0; }  // s
  // Where each heartbeat reads the count of messages the node's transport dropped unread for want
  // of a valid MAC (DdsEndpoint::unauthenticated_count: a lock, no allocation); unset: 0 (no
  // secret, in process). Set before start().
  void set_unauthenticated_source(std::function<std::uint64_t()> count) {
    unauthenticated_ = std::move(count);
  }
  // How the set-up of its part reports progress (setup_progress.h): when a line is due and where
  // it goes; default: after 3 s, at most one every 5 s, to spdlog info. Set before the ASSIGN.
  void set_setup_progress(util::ProgressPacing pacing, SetupProgress::Print print) {
    setup_pacing_ = std::move(pacing);
    setup_print_ = std::move(print);
  }
  // Receive + send lag injected for the message about to be handled (s); goes into its feedback.
  void set_injected_lag(double seconds) { injected_lag_ = seconds; }

  // Held and not yet settled: runs on_settle() once. The node loop calls it after a hold.
  void settle_hold() {
    if (held_ && !settled_) {
      settled_ = true;
      on_settle();
    }
  }

  // Asynchronous answers (see the contract above).
  bool asynchronous() const { return source_ != nullptr; }
  // Without the node's lock: waits on the answer source alone (CLOCK_MONOTONIC ns).
  void await_answers(std::int64_t deadline_ns) {
    if (source_) source_->wait(deadline_ns);
  }
  // With the node's lock: forwards every answer ready now (or the HOLD a fault makes).
  void take_answers(const Send& send);
  // Stopped, at rest, and its final heartbeat not yet sent: the loop sends it now (once).
  std::optional<transport::Message> final_heartbeat_due();
  bool at_rest() const { return !source_ || source_->rested(); }

  bool assigned() const { return assigned_; }
  bool held() const { return held_; }
  bool stopped() const { return stopped_; }
  const std::string& run_id() const { return run_id_; }
  const Assign& assignment() const { return assignment_; }
  std::int32_t node_id() const { return node_id_; }
  std::int64_t last_step() const { return last_step_; }
  const RejectCounters& rejected() const { return rejected_; }
  std::string label() const;

 protected:
  // Builds the node's part; returns how many storeys/actuators it hosts. Throws on a bad part.
  virtual int configure(const Assign& assign) = 0;
  // From configure(): the phase of the set-up starting now, named in its progress lines.
  void setup_phase(std::string what) {
    if (setup_progress_) setup_progress_->phase(std::move(what));
  }
  // One step. Fills force (and realised for actuators), one entry per hosted storey. Throws
  // std::invalid_argument on a command of the wrong size before it changes any state. Never
  // called on a node with an answer source (the default throws std::logic_error saying so).
  virtual void compute(const Command& command, Feedback& feedback);
  virtual void on_hold() {}
  // Once per hold, after the HOLD has been reported (so its cost never delays the report):
  // whatever the node does to come to rest (the emulator's rate-limited ramp).
  virtual void on_settle() {}
  // Real time: the servo period (s) when the node runs a servo loop faster than the integrator,
  // else 0 (answer each command with compute()). Asked once, after configure().
  virtual double servo_period() const { return 0.0; }
  // Streaming: take the command (check sizes before changing state; throw invalid_argument).
  virtual void load(const Command& /*command*/) {}
  // Streaming: one servo period; fills force and realised as compute() does.
  virtual void tick(Feedback& /*feedback*/) {}
  // Non-empty: why this command must not be acted on (checked before any delay stage or block).
  virtual std::string refusal(const Command& /*command*/) { return {}; }
  // On STOP, before the final heartbeat (after the answer source, if any, was told to stop).
  virtual void on_stop() {}
  // What a node adds to each heartbeat (a controller's link report).
  virtual void fill_heartbeat(Heartbeat& /*heartbeat*/) const {}
  // The source of the node's answers when they come on their own (see "asynchronous"), owned by
  // the subclass and alive as long as it; nullptr: compute() answers each command. Asked once,
  // after configure().
  virtual AnswerSource* answer_source() { return nullptr; }

 private:
  std::optional<transport::Message> on_assign(const transport::Message& message);
  // Throws std::invalid_argument naming what the assignment cannot be (configure_error_).
  void build_part(const Assign& assign);
  void on_command(const transport::Message& message, const Send& send);
  void answer(const transport::Message& message, const Send& send);
  // The node holds (HOLD, its own watchdog, a fault): its source and on_hold() are told.
  void enter_hold();
  // Whether a control message (ASSIGN, COMMAND, HOLD, STOP) came from the coordinator that
  // assigned this node, on this node's own topic; counts it not entitled otherwise.
  bool entitled(const transport::Message& message);
  bool in_range(const Command& command) const;
  // The receive chains' sensor errors on the computed answer (see "node delay stages").
  void apply_receive_sensors();
  transport::Message heartbeat_message(bool final) const;
  std::uint64_t coordinator_writer_ = 0;  // the first accepted ASSIGN's writer
  std::int32_t node_id_;
  config::NodeSpec::Kind kind_;
  std::string expected_run_id_, run_id_;
  bool assigned_ = false, held_ = false, settled_ = false, stopped_ = false;
  std::string configure_error_;
  int hosted_ = 0;
  Assign assignment_;
  std::int64_t last_step_ = 0;  // commands start at step 1
  std::int64_t max_step_gap_ = 1;
  double injected_lag_ = 0.0;
  RejectCounters rejected_;
  std::function<std::uint64_t()> unauthenticated_;
  // The set-up's progress: its pacing, its lines' sink, and the one running (during build_part).
  static constexpr double kSetupWatchSeconds = 0.5;  // s between the watcher's looks
  util::ProgressPacing setup_pacing_;
  SetupProgress::Print setup_print_;
  std::optional<SetupProgress> setup_progress_;
  Command command_;
  Feedback feedback_;
  transport::Message reply_;  // the synchronous reply, packed in place
  bool streaming_ = false;
  // Asynchronous: the envelope of each recent step's command, by step % kEnvelopes.
  AnswerSource* source_ = nullptr;
  bool final_heartbeat_sent_ = false;
  struct Envelope {
    std::int64_t step = -1, echo_ns = 0, received_ns = 0;
    double injected_lag = 0.0;
  };
  static constexpr std::size_t kEnvelopes = 1024;
  std::vector<Envelope> envelopes_;
  Feedback async_feedback_;
  transport::Message async_reply_;
  // Streaming: the newest loaded command's envelope (step 0 = none yet) and the servo counters.
  std::int64_t stream_step_ = 0, stream_echo_ns_ = 0, stream_received_ns_ = 0;
  double stream_injected_lag_ = 0.0, stream_period_ = 0.0;
  std::int64_t servo_samples_ = 0;
  std::uint64_t servo_overruns_ = 0;
  // Simulated-time stages of the node's spec, one chain per hosted entry (empty: none).
  std::vector<core::DelayChain> receive_chains_, send_chains_;
};

}  // namespace rths::runtime
