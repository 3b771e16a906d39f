#include "coordinator/feedback_intake.h"

#include <cmath>

#include "runtime/node/schema.h"

namespace rths::coordinator {

using runtime::Verdict;

namespace {

// A controller's diagnostic channels a feedback may carry: a frame of at most
// runtime::kMaxControllerFrameBytes holds at most this many 4-byte fields.
constexpr int kMaxDiagnostics = 512;

// FNV-1a, 64 bit: tells two payloads apart. Not a defence against a chosen collision; the
// writer check is (a forger cannot answer from the node's own writer).
std::uint64_t hash_of(const std::string& bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

std::string arrival(const char* which, std::int64_t sent_ns, std::int64_t received_ns,
                    std::uint64_t writer) {
  return std::string(which) + " arrived at realtime_ns " + std::to_string(received_ns) +
         " (sent_ns " + std::to_string(sent_ns) +
         (writer != 0 ? ", writer " + std::to_string(writer) : std::string()) + ")";
}

}  // namespace

FeedbackIntake::FeedbackIntake(std::string run_id, const std::vector<IntakeNode>& nodes,
                               double max_realised)
    : run_id_(std::move(run_id)), max_realised_(max_realised) {
  for (const IntakeNode& shape : nodes) {
    auto node = std::make_unique<Node>();
    node->shape = shape;
    node->awaited.store(shape.awaited, std::memory_order_relaxed);
    node->link.set_node_id(shape.id);
    nodes_[shape.id] = std::move(node);
  }
}

void FeedbackIntake::pin(int node_id, std::uint64_t writer) {
  std::lock_guard lock(producer_mutex_);
  nodes_.at(node_id)->writer = writer;
}

void FeedbackIntake::raise(int node_id, std::string what) {
  if (faulted_.load(std::memory_order_relaxed)) return;  // the first fault stands
  fault_.node_id = node_id;
  fault_.what = "integrity fault: " + std::move(what);
  faulted_.store(true, std::memory_order_release);
}

Verdict FeedbackIntake::judge(const transport::Message& message, Node*& node) {
  const Verdict envelope = runtime::check_envelope(message, run_id_);
  if (envelope != Verdict::kAccept) return envelope;
  const auto it = nodes_.find(message.node_id);
  if (it == nodes_.end()) return Verdict::kUnknownNode;
  node = it->second.get();
  if (message.topic_node != message.node_id) return Verdict::kNotEntitled;
  if (node->writer != 0 && message.writer != 0 && message.writer != node->writer) {
    raise(message.node_id,
          "another participant answers as node " + std::to_string(message.node_id) +
              ": its answer to step " + std::to_string(message.step) +
              arrival("", message.sent_ns, message.received_ns, message.writer) +
              (node->answers == 0
                   ? "; the node itself (writer " + std::to_string(node->writer) +
                         ") has not answered yet"
                   : "; the node's own answer to step " + std::to_string(node->last_answer) +
                         arrival("", node->accepted.sent_ns, node->accepted.received_ns,
                                 node->writer)));
    return Verdict::kNotEntitled;
  }
  const std::int64_t awaited = awaited_.load(std::memory_order_acquire);
  const Verdict order = runtime::check_step(message.step, node->last_answer, awaited);
  if (order == Verdict::kAccept && message.step == awaited && !echoes_command(message, *node))
    return Verdict::kOutOfOrder;
  return order;
}

bool FeedbackIntake::echoes_command(const transport::Message& message, Node& node) const {
  // The loop stores the new awaited step before the new command's stamp: if the step moved on
  // while the stamp was read, the stamp may be the next command's, and this answer is to an
  // older step now (not checked, as every older step's answer).
  const std::int64_t echo = node.command_echo.load(std::memory_order_acquire);
  if (awaited_.load(std::memory_order_acquire) != message.step) return true;
  return echo >= 0 && message.echo_ns == echo;
}

bool FeedbackIntake::values_in_range(const runtime::Feedback& f) const {
  return runtime::finite_within(f.force(), 0.0) &&
         runtime::finite_within(f.realised(), max_realised_) && std::isfinite(f.injected_lag()) &&
         f.injected_lag() >= 0.0 && f.command_received_ns() >= 0 && f.sampled_ns() >= 0 &&
         f.servo_sample() >= 0 && std::isfinite(f.controller_round_trip()) &&
         f.controller_round_trip() >= 0.0 &&
         runtime::finite_within(f.controller_diagnostics(), 0.0) &&
         f.controller_diagnostics_size() <= kMaxDiagnostics;
}

Verdict FeedbackIntake::judge_repeat(const transport::Message& message, Node& node,
                                     std::uint64_t hash, std::int64_t servo_sample) {
  if (servo_sample > node.servo_sample) return Verdict::kAccept;
  if (servo_sample == node.servo_sample && hash != node.accepted.payload_hash)
    raise(message.node_id,
          "two different answers to step " + std::to_string(message.step) + " from node " +
              std::to_string(message.node_id) + ": the first" +
              arrival("", node.accepted.sent_ns, node.accepted.received_ns, node.accepted.writer) +
              ", the second" + arrival("", message.sent_ns, message.received_ns, message.writer));
  return Verdict::kDuplicate;
}

void FeedbackIntake::record_answer(const transport::Message& message, Node& node,
                                   std::uint64_t hash) {
  node.accepted = {hash, message.writer, message.sent_ns, message.received_ns};
  node.last_answer = message.step;
  ++node.answers;
  const runtime::Feedback& feedback = node.box.slot().feedback;
  runtime::LinkSample& link = node.link;
  link.set_answered_step(message.step);
  link.set_answers(node.answers);
  link.set_injected_lag(feedback.injected_lag());
  link.set_round_trip(static_cast<double>(message.received_ns - message.echo_ns) * 1e-9);
  link.set_one_way_down(static_cast<double>(feedback.command_received_ns() - message.echo_ns) *
                        1e-9);
  link.set_one_way_up(static_cast<double>(message.received_ns - message.sent_ns) * 1e-9);
  link.set_controller_round_trip(feedback.controller_round_trip());
  link.set_controller_status(feedback.controller_status());
  // Copied in place: the sample's field keeps its capacity from step to step.
  link.mutable_controller_diagnostics()->Resize(feedback.controller_diagnostics_size(), 0.0);
  for (int i = 0; i < feedback.controller_diagnostics_size(); ++i)
    link.set_controller_diagnostics(i, feedback.controller_diagnostics(i));
}

bool FeedbackIntake::offer(const transport::Message& message) {
  std::lock_guard lock(producer_mutex_);
  const bool faulted_before = faulted_.load(std::memory_order_relaxed);
  Node* node = nullptr;
  const Verdict verdict = judge(message, node);
  const bool same_step = verdict == Verdict::kDuplicate;
  if (verdict != Verdict::kAccept && !same_step) {
    rejected_.count(verdict);
    return faulted_.load(std::memory_order_relaxed) != faulted_before;
  }
  ArrivedFeedback& arrived = node->box.slot();
  runtime::Feedback& feedback = arrived.feedback;
  const int expected = node->shape.values;
  if (!runtime::unpack(message, feedback) || feedback.force_size() != expected ||
      (node->shape.emulator && feedback.realised_size() != expected)) {
    rejected_.count(Verdict::kGarbage);
    return false;
  }
  if (!values_in_range(feedback)) {
    rejected_.count(Verdict::kOutOfRange);
    return false;
  }
  const std::uint64_t hash = hash_of(message.payload);
  if (same_step) {
    const Verdict repeat = judge_repeat(message, *node, hash, feedback.servo_sample());
    if (repeat != Verdict::kAccept) {
      rejected_.count(repeat);
      return faulted_.load(std::memory_order_relaxed) != faulted_before;
    }
    node->accepted = {hash, message.writer, message.sent_ns, message.received_ns};
  } else {
    record_answer(message, *node, hash);
  }
  node->servo_sample = feedback.servo_sample();
  arrived.answered_step = node->last_answer;
  arrived.answers = node->answers;
  arrived.link = node->link;
  node->box.publish();
  const std::int64_t awaited = awaited_.load(std::memory_order_acquire);
  const auto waited_for = [](const Node& n) { return n.awaited.load(std::memory_order_acquire); };
  if (same_step || message.step != awaited || !waited_for(*node)) return false;
  for (const auto& [id, other] : nodes_)
    if (waited_for(*other) && other->last_answer != awaited) return false;
  return true;
}

runtime::RejectCounters FeedbackIntake::rejected() const {
  std::lock_guard lock(producer_mutex_);
  return rejected_;
}

}  // namespace rths::coordinator
