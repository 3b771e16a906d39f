#include "runtime/node/node_service.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>

#include "runtime/node/lag.h"
#include "runtime/node/plan.h"
#include "runtime/node/schema.h"
#include "study/study.h"

namespace rths::runtime {
namespace {

// The one lag rule (study/study.h), as the coordinator applied it at load: a node does not take
// the coordinator's word for the lags it injects. Throws std::invalid_argument naming the field.
void validate_assigned_lags(const Assign& assign) {
  for (const auto& [name, lag] : {std::pair{"receive_lag", &assign.node().receive_lag()},
                                  std::pair{"send_lag", &assign.node().send_lag()}})
    study::validate_link_lag(*lag, std::string("node.") + name, assign.study().allow_long_lag(),
                             "the assigned study");
}

}  // namespace

NodeService::NodeService(std::int32_t node_id, config::NodeSpec::Kind kind,
                         std::string expected_run_id)
    : node_id_(node_id),
      kind_(kind),
      expected_run_id_(std::move(expected_run_id)),
      setup_print_([](const std::string& line) { spdlog::info("{}", line); }) {}

std::string NodeService::label() const {
  return "node " + std::to_string(node_id_) + " (" + node_kind_name(kind_) + ")";
}

transport::Message NodeService::announce() const {
  Announce a;
  a.set_schema_version(kSchemaVersion);
  a.set_node_id(node_id_);
  a.set_kind(kind_);
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  a.set_host(host);
  a.set_pid(static_cast<int>(getpid()));
  return pack(expected_run_id_, node_id_, ANNOUNCE, 0, a);
}

transport::Message NodeService::heartbeat() const { return heartbeat_message(false); }

transport::Message NodeService::heartbeat_message(bool final) const {
  Heartbeat h;
  h.set_node_id(node_id_);
  h.set_last_step(last_step_);
  h.set_rejected(rejected_.total());
  h.set_servo_ticks(static_cast<std::uint64_t>(servo_samples_));
  h.set_servo_overruns(servo_overruns_);
  rejected_.fill(*h.mutable_rejected_by_cause());
  h.mutable_rejected_by_cause()->set_unauthenticated(unauthenticated_ ? unauthenticated_() : 0);
  h.set_final(final);
  fill_heartbeat(h);
  return pack(run_id_, node_id_, HEARTBEAT, last_step_, h);
}

bool NodeService::entitled(const transport::Message& message) {
  const bool own_topic = message.topic_node == node_id_ && message.node_id == node_id_;
  const bool own_writer =
      coordinator_writer_ == 0 || message.writer == 0 || message.writer == coordinator_writer_;
  if (own_topic && own_writer) return true;
  rejected_.count(Verdict::kNotEntitled);
  return false;
}

bool NodeService::in_range(const Command& command) const {
  const config::SafetyLimits& limits = assignment_.study().deployment().limits();
  return std::isfinite(command.time()) && command.time() >= 0.0 &&
         finite_within(command.drift(), 2.0 * limits.max_displacement()) &&
         finite_within(command.drift_velocity(), 2.0 * limits.max_velocity());
}

std::vector<transport::Message> NodeService::start() { return {announce()}; }

void NodeService::compute(const Command& /*command*/, Feedback& /*feedback*/) {
  throw std::logic_error(label() + ": compute() called on a node whose answers come from its " +
                         "answer source");
}

std::optional<transport::Message> NodeService::on_assign(const transport::Message& message) {
  if (!entitled(message)) return std::nullopt;
  Assign assign;
  if (!unpack(message, assign)) {
    rejected_.count(Verdict::kGarbage);
    return std::nullopt;
  }
  if (!assigned_) {
    if (message.run_id.empty() ||
        (!expected_run_id_.empty() && message.run_id != expected_run_id_)) {
      rejected_.count(Verdict::kForeignRun);
      return std::nullopt;
    }
    run_id_ = message.run_id;
    coordinator_writer_ = message.writer;
    assignment_ = assign;
    const auto& deployment = assign.study().deployment();
    if (deployment.clock() == config::Deployment::REAL_TIME && assign.dt() > 0) {
      const double window = liveliness_timeout(deployment) / assign.dt();
      max_step_gap_ = static_cast<std::int64_t>(window) + 1;
    }
    assigned_ = true;
    try {
      build_part(assign);
    } catch (const std::exception& e) {
      configure_error_ = label() + ": " + e.what();
      spdlog::error("{}", configure_error_);
    }
    setup_progress_.reset();  // built or failed, its watcher ends here
  }
  // A repeated ASSIGN (the coordinator re-sends until it hears READY) gets the same answer.
  Ready ready;
  ready.set_node_id(node_id_);
  ready.set_storeys(hosted_);
  ready.set_error(configure_error_);
  return pack(run_id_, node_id_, READY, 0, ready);
}

void NodeService::build_part(const Assign& assign) {
  setup_progress_.emplace(label(), setup_pacing_, setup_print_);
  setup_progress_->watch(kSetupWatchSeconds);
  if (assign.schema_version() != kSchemaVersion)
    throw std::invalid_argument("schema version " + std::to_string(assign.schema_version()) +
                                ", this node speaks " + std::to_string(kSchemaVersion));
  validate_assigned_lags(assign);
  hosted_ = configure(assign);
  setup_phase("building its delay stages");
  const auto chains = [&](const google::protobuf::RepeatedPtrField<config::DelayStage>& stages) {
    std::vector<core::DelayChain> out;
    if (stages.empty()) return out;
    for (int i = 0; i < hosted_; ++i)
      out.push_back(study::make_delay_chain(stages, assign.dt(), assign.base_dir()));
    return out;
  };
  receive_chains_ = chains(assign.node().receive_delay());
  send_chains_ = chains(assign.node().send_delay());
  source_ = answer_source();
  if (source_ && (!receive_chains_.empty() || !send_chains_.empty() ||
                  LagInjector(assign.node().send_lag()).active()))
    throw std::invalid_argument(
        "this node answers when its controller does, not once per command: receive_delay, "
        "send_delay and send_lag cannot act on its answers (inject the controller link's lag "
        "at the controller, or use receive_lag)");
  if (source_) envelopes_.assign(kEnvelopes, Envelope{});
  stream_period_ = servo_period();
  streaming_ =
      assign.study().deployment().clock() == config::Deployment::REAL_TIME && stream_period_ > 0;
  if (streaming_ && !send_chains_.empty())
    throw std::invalid_argument(
        "send_delay acts once per command, but a servo loop faster than the integrator "
        "streams feedback every servo period; inject the lag with send_lag instead");
  setup_progress_->finish();
}

void NodeService::enter_hold() {
  held_ = true;
  if (source_) source_->hold();
  on_hold();
}

std::optional<transport::Message> NodeService::hold_on_own(const std::string& reason) {
  if (held_ || stopped_) return std::nullopt;
  enter_hold();
  spdlog::error("{}: holding on its own at step {} (realtime_ns {}): {}", label(), last_step_,
                transport::realtime_ns(), reason);
  Hold hold;
  hold.set_reason(reason);
  return pack(run_id_, node_id_, HOLD, last_step_, hold);
}

std::optional<transport::Message> NodeService::servo_tick(bool overrun) {
  if (!streaming_ || held_ || stopped_ || stream_step_ == 0) return std::nullopt;
  if (overrun) ++servo_overruns_;
  feedback_.Clear();
  tick(feedback_);
  feedback_.set_command_received_ns(stream_received_ns_);
  feedback_.set_injected_lag(stream_injected_lag_);
  feedback_.set_servo_sample(++servo_samples_);
  feedback_.set_sampled_ns(transport::realtime_ns());
  transport::Message reply = pack(run_id_, node_id_, FEEDBACK, stream_step_, feedback_);
  reply.echo_ns = stream_echo_ns_;
  return reply;
}

std::vector<transport::Message> NodeService::handle(const transport::Message& message) {
  std::vector<transport::Message> replies;
  handle(message, [&replies](const transport::Message& m) { replies.push_back(m); });
  return replies;
}

void NodeService::handle(const transport::Message& message, const Send& send) {
  if (!assigned_) {
    // Nothing but an ASSIGN concerns a node that is not part of a run yet.
    if (message.kind == ASSIGN)
      if (auto ready = on_assign(message)) send(*ready);
    return;
  }
  const Verdict envelope = check_envelope(message, run_id_);
  if (envelope != Verdict::kAccept) {
    rejected_.count(envelope);
    return;
  }
  switch (message.kind) {
    case ASSIGN:
      if (auto ready = on_assign(message)) send(*ready);
      return;
    case COMMAND: return on_command(message, send);
    case HOLD:
      if (!entitled(message) || held_) return;
      enter_hold();
      {
        Hold hold;
        unpack(message, hold);
        spdlog::warn("{}: HOLD at step {} (realtime_ns {}): {}", label(), last_step_,
                     transport::realtime_ns(), hold.reason());
      }
      return;
    case STOP:
      if (!entitled(message)) return;
      stopped_ = true;
      if (source_) source_->stop();
      on_stop();
      if (!source_) send(heartbeat_message(true));  // else final_heartbeat_due(), once at rest
      return;
    default: return;  // heartbeats only refresh liveliness, which the loop tracks
  }
}

void NodeService::apply_receive_sensors() {
  if (receive_chains_.empty() || command_.drift_size() != hosted_) return;
  for (int i = 0; i < hosted_; ++i) {
    auto& chain = receive_chains_[static_cast<std::size_t>(i)];
    if (i < feedback_.force_size()) feedback_.set_force(i, chain.measure_force(feedback_.force(i)));
    // The chain's output is the drift compute() acted on; its sensors read off it by this much.
    if (i < feedback_.realised_size())
      feedback_.set_realised(i, feedback_.realised(i) + chain.measured() - command_.drift(i));
  }
}

void NodeService::on_command(const transport::Message& message, const Send& send) {
  if (!entitled(message) || held_ || stopped_ || !configure_error_.empty()) return;
  const Verdict order = check_step(message.step, last_step_, last_step_ + max_step_gap_);
  if (order != Verdict::kAccept) return rejected_.count(order);
  if (!unpack(message, command_)) return rejected_.count(Verdict::kGarbage);
  if (!in_range(command_)) return rejected_.count(Verdict::kOutOfRange);
  if (const std::string why = refusal(command_); !why.empty()) {
    if (auto hold =
            hold_on_own("refused the command of step " + std::to_string(message.step) + ": " + why))
      send(*hold);
    return;
  }
  feedback_.Clear();
  if (!receive_chains_.empty() && command_.drift_size() == hosted_ &&
      command_.drift_velocity_size() == hosted_) {
    for (int i = 0; i < hosted_; ++i) {
      const double velocity = command_.drift_velocity(i);
      command_.set_drift(i,
                         receive_chains_[i].step({command_.time(), command_.drift(i), velocity}));
    }
  }
  if (source_) {
    Envelope& e = envelopes_[static_cast<std::size_t>(message.step) % kEnvelopes];
    e = Envelope{message.step, message.sent_ns, message.received_ns, injected_lag_};
    last_step_ = message.step;
    return source_->dispatch(message.step, command_);
  }
  try {
    if (streaming_)
      load(command_);
    else
      compute(command_, feedback_);  // checks sizes before it changes any state
  } catch (const std::invalid_argument& e) {
    spdlog::warn("{}: rejected command of step {}: {}", label(), message.step, e.what());
    return rejected_.count(Verdict::kGarbage);
  }
  if (!streaming_) return answer(message, send);
  last_step_ = stream_step_ = message.step;
  stream_echo_ns_ = message.sent_ns;
  stream_received_ns_ = message.received_ns;
  stream_injected_lag_ = injected_lag_;
}

// After compute(): FEEDBACK through the send stages, echoing the command's stamp, packed into
// reply_ (no allocation once warm).
void NodeService::answer(const transport::Message& message, const Send& send) {
  apply_receive_sensors();
  if (!send_chains_.empty())
    for (int i = 0; i < hosted_ && i < feedback_.force_size(); ++i)
      feedback_.set_force(i, send_chains_[i].step({command_.time(), feedback_.force(i), 0.0}));
  last_step_ = message.step;
  feedback_.set_command_received_ns(message.received_ns);
  feedback_.set_injected_lag(injected_lag_);
  pack_into(reply_, run_id_, node_id_, FEEDBACK, message.step, feedback_);
  reply_.echo_ns = message.sent_ns;
  send(reply_);
}

}  // namespace rths::runtime

namespace rths::runtime {

void NodeService::take_answers(const Send& send) {
  if (!source_) return;
  for (;;) {
    async_feedback_.Clear();
    const AnswerSource::Next a = source_->next(async_feedback_);
    if (a.kind == AnswerSource::Next::Kind::kNone) return;
    if (a.kind == AnswerSource::Next::Kind::kFault) {
      if (auto hold = hold_on_own("step " + std::to_string(last_step_) + ": " + a.fault))
        send(*hold);
      continue;  // held now: next() brings the source to rest
    }
    if (held_ || stopped_) continue;
    const Envelope& e = envelopes_[static_cast<std::size_t>(a.step) % kEnvelopes];
    if (a.step <= 0 || e.step != a.step) continue;  // a step too old to echo
    async_feedback_.set_command_received_ns(e.received_ns);
    async_feedback_.set_injected_lag(e.injected_lag);
    pack_into(async_reply_, run_id_, node_id_, FEEDBACK, a.step, async_feedback_);
    async_reply_.echo_ns = e.echo_ns;
    send(async_reply_);
  }
}

std::optional<transport::Message> NodeService::final_heartbeat_due() {
  if (!source_ || !stopped_ || final_heartbeat_sent_ || !source_->rested()) return std::nullopt;
  final_heartbeat_sent_ = true;
  return heartbeat_message(true);
}

}  // namespace rths::runtime
