#include "controller_node/controller_answers.h"

#include <spdlog/spdlog.h>

#include "runtime/rt/clock.h"

namespace rths::controller_node {

ControllerAnswers::ControllerAnswers(std::unique_ptr<ControllerExchange> exchange,
                                     std::string label)
    : exchange_(std::move(exchange)),
      label_(std::move(label)),
      drift_(exchange_->actuators(), 0.0),
      velocity_(drift_) {}

void ControllerAnswers::dispatch(std::int64_t step, const runtime::Command& command) {
  const int n = static_cast<int>(drift_.size());
  if (command.drift_size() != n || command.drift_velocity_size() != n) {
    dispatch_fault_ = "command of step " + std::to_string(step) + " has " +
                      std::to_string(command.drift_size()) + " drifts for " + std::to_string(n) +
                      " actuators";
    return;
  }
  for (int i = 0; i < n; ++i) {
    drift_[static_cast<std::size_t>(i)] = command.drift(i);
    velocity_[static_cast<std::size_t>(i)] = command.drift_velocity(i);
  }
  if (!exchange_->send_command(step, command.time(), drift_, velocity_))
    dispatch_fault_ = exchange_->fault();
}

runtime::AnswerSource::Next ControllerAnswers::next(runtime::Feedback& feedback) {
  Next out;
  if (!dispatch_fault_.empty()) {
    out.kind = Next::Kind::kFault;
    out.fault = "controller: " + dispatch_fault_;
    dispatch_fault_.clear();
    return out;
  }
  const std::int64_t now = exchange_->now_ns();
  if (exchange_->holding()) {
    hold_done_ = exchange_->hold_step(now);
    if (hold_done_ && stop_requested_ && !stop_sent_) {
      stop_sent_ = true;
      exchange_->send_stop();
    }
    return out;
  }
  const ControllerExchange::Answer a = exchange_->next(now);
  if (a.outcome == ControllerExchange::Outcome::kNone) return out;
  if (a.outcome == ControllerExchange::Outcome::kFault) {
    out.kind = Next::Kind::kFault;
    out.fault = "controller: " + a.fault;
    return out;
  }
  for (std::size_t i = 0; i < drift_.size(); ++i) {
    feedback.add_realised((*a.displacement)[i]);
    feedback.add_force((*a.force)[i]);
  }
  for (const double v : *a.diagnostics) feedback.add_controller_diagnostics(v);
  feedback.set_controller_round_trip(a.round_trip);
  feedback.set_controller_status(static_cast<std::int32_t>(a.status));
  out.kind = Next::Kind::kAnswer;
  out.step = a.step;
  return out;
}

void ControllerAnswers::hold() {
  if (exchange_->holding()) return;
  exchange_->begin_hold(exchange_->now_ns());
  spdlog::warn("{}: HOLD frames (status {}) to the controller {}, holding the measured position",
               label_, kStatusHold, exchange_->peer());
}

void ControllerAnswers::stop() {
  stop_requested_ = true;
  if (!exchange_->holding()) exchange_->begin_hold(exchange_->now_ns());
}

}  // namespace rths::controller_node
