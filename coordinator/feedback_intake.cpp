#include "coordinator/feedback_intake.h"

#include "runtime/schema.h"

namespace rths::coordinator {

using runtime::Verdict;

FeedbackIntake::FeedbackIntake(std::string run_id, const std::vector<IntakeNode>& nodes)
    : run_id_(std::move(run_id)) {
  for (const IntakeNode& shape : nodes) {
    auto node = std::make_unique<Node>();
    node->shape = shape;
    node->link.set_node_id(shape.id);
    nodes_[shape.id] = std::move(node);
  }
}

bool FeedbackIntake::offer(const transport::Message& message) {
  std::lock_guard lock(producer_mutex_);
  Verdict verdict = runtime::check_envelope(message, run_id_);
  const auto it = nodes_.find(message.node_id);
  if (verdict == Verdict::kAccept && it == nodes_.end()) verdict = Verdict::kUnknownNode;
  if (verdict != Verdict::kAccept) {
    rejected_.count(verdict);
    return false;
  }
  Node& node = *it->second;
  const std::int64_t awaited = awaited_.load(std::memory_order_acquire);
  const Verdict order = runtime::check_step(message.step, node.last_answer, awaited);
  const bool same_step = order == Verdict::kDuplicate;
  if (order != Verdict::kAccept && !same_step) {
    rejected_.count(order);
    return false;
  }
  ArrivedFeedback& arrived = node.box.slot();
  runtime::Feedback& feedback = arrived.feedback;
  const int expected = node.shape.values;
  if (!runtime::unpack(message, feedback) || feedback.force_size() != expected ||
      (node.shape.emulator && feedback.realised_size() != expected)) {
    rejected_.count(Verdict::kGarbage);
    return false;
  }
  if (same_step && feedback.servo_sample() <= node.servo_sample) {
    rejected_.count(order);
    return false;
  }
  node.servo_sample = feedback.servo_sample();
  if (!same_step) {
    node.last_answer = message.step;
    ++node.answers;
    runtime::LinkSample& link = node.link;
    link.set_answered_step(message.step);
    link.set_injected_lag(feedback.injected_lag());
    link.set_round_trip(static_cast<double>(message.received_ns - message.echo_ns) * 1e-9);
    link.set_one_way_down(static_cast<double>(feedback.command_received_ns() - message.echo_ns) *
                          1e-9);
    link.set_one_way_up(static_cast<double>(message.received_ns - message.sent_ns) * 1e-9);
  }
  arrived.answered_step = node.last_answer;
  arrived.answers = node.answers;
  arrived.link = node.link;
  node.box.publish();
  if (same_step || message.step != awaited || !node.shape.awaited) return false;
  for (const auto& [id, other] : nodes_)
    if (other->shape.awaited && other->last_answer != awaited) return false;
  return true;
}

runtime::RejectCounters FeedbackIntake::rejected() const {
  std::lock_guard lock(producer_mutex_);
  return rejected_;
}

}  // namespace rths::coordinator
