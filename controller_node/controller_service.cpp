#include "controller_node/controller_service.h"

#include <spdlog/spdlog.h>

#include <stdexcept>

#include "runtime/node/plan.h"

namespace rths::controller_node {

ControllerService::ControllerService(std::int32_t node_id, std::string expected_run_id)
    : NodeService(node_id, config::NodeSpec::CONTROLLER, std::move(expected_run_id)) {}

const runtime::ControllerReport& ControllerService::report() const {
  static const runtime::ControllerReport none;
  return exchange_ ? exchange_->report() : none;
}

int ControllerService::configure(const runtime::Assign& assign) {
  if (!assign.node().has_controller())
    throw std::invalid_argument("a CONTROLLER node needs its `controller` link");
  const config::ControllerLink& link = assign.node().controller();
  const config::Deployment& deployment = assign.study().deployment();
  ExchangeSettings settings;
  settings.actuators = assign.actuators_size();
  settings.real_time = deployment.clock() == config::Deployment::REAL_TIME;
  settings.reply_timeout = link.reply_timeout_ms() > 0 ? link.reply_timeout_ms() * 1e-3
                           : settings.real_time        ? assign.dt()
                                                       : 1.0;
  settings.lost_window =
      settings.real_time ? runtime::max_missed_answers(deployment, assign.dt()) : 1;
  settings.max_drift = 2.0 * deployment.limits().max_displacement();
  settings.max_force = link.max_force();
  exchange_ = std::make_unique<ControllerExchange>(link, settings);
  drift_.assign(static_cast<std::size_t>(settings.actuators), 0.0);
  velocity_ = drift_;
  spdlog::info("{}: UDP {} -> controller {}, frames of {} and {} bytes, reply timeout {} ms",
               label(), link.local_address() + ":" + std::to_string(link.local_port()),
               exchange_->peer(), frame_size(link.command()), frame_size(link.feedback()),
               settings.reply_timeout * 1e3);
  return settings.actuators;
}

void ControllerService::compute(const runtime::Command& command, runtime::Feedback& feedback) {
  const int n = static_cast<int>(drift_.size());
  if (command.drift_size() != n || command.drift_velocity_size() != n)
    throw std::invalid_argument(label() + ": command has " + std::to_string(command.drift_size()) +
                                " drifts for " + std::to_string(n) + " actuators");
  for (int i = 0; i < n; ++i) {
    drift_[i] = command.drift(i);
    velocity_[i] = command.drift_velocity(i);
  }
  const ControllerExchange::Answer a = exchange_->exchange(command.time(), drift_, velocity_);
  answered_ = a.outcome == ControllerExchange::Outcome::kAnswered;
  fault_ = a.outcome == ControllerExchange::Outcome::kFault ? "controller: " + a.fault : "";
  if (!answered_) return;
  for (int i = 0; i < n; ++i) {
    feedback.add_realised(a.displacement[i]);
    feedback.add_force(a.force[i]);
  }
  feedback.set_controller_round_trip(a.round_trip);
  feedback.set_controller_status(static_cast<std::int32_t>(a.status));
}

std::string ControllerService::failure() {
  std::string why = std::move(fault_);
  fault_.clear();
  return why;
}

void ControllerService::on_hold() {
  if (!exchange_) return;
  const bool sent = exchange_->send_status(kStatusHold);
  spdlog::warn("{}: HOLD {} to the controller {} (status {} in a command frame)", label(),
               sent ? "sent" : "could not be sent", exchange_->peer(), kStatusHold);
}

void ControllerService::on_stop() {
  if (!exchange_) return;
  exchange_->send_status(kStatusStop);
  const runtime::ControllerReport& r = exchange_->report();
  spdlog::info(
      "{}: controller {}: {} frames sent, {} accepted, {} late, {} lost; rejected: wrong source "
      "{}, wrong size {}, repeated counter {}, unexpected counter {}, not finite {}, out of range "
      "{}, bad status {}; round trip last {:.3f} ms, max {:.3f} ms{}",
      label(), exchange_->peer(), r.frames_sent(), r.frames_accepted(), r.late(), r.lost(),
      r.wrong_source(), r.wrong_size(), r.repeated_counter(), r.unexpected_counter(),
      r.non_finite(), r.out_of_range(), r.bad_status(), r.round_trip_last() * 1e3,
      r.round_trip_max() * 1e3, r.last_reject().empty() ? "" : "; newest: " + r.last_reject());
}

void ControllerService::fill_heartbeat(runtime::Heartbeat& heartbeat) const {
  if (exchange_) *heartbeat.mutable_controller() = exchange_->report();
}

}  // namespace rths::controller_node
