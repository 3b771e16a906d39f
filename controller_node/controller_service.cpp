#include "controller_node/controller_service.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <stdexcept>

#include "runtime/node/plan.h"
#include "runtime/record/node_health.h"

namespace rths::controller_node {
namespace {

// Real time: lost frames in a row before the node holds, so that it holds (naming the
// controller's silence) before the coordinator's answer window passes: the first frame of a
// silence is lost a reply timeout after it left, each later one a dt after the one before. A
// margin of an eighth of the window (2 steps of a 21-step window, none of a 3-step one) lets its
// HOLD reach the coordinator before its own window on the answers' age fires.
int lost_window(const config::Deployment& deployment, double dt, double reply) {
  const int window = runtime::max_missed_answers(deployment, dt);
  return std::max(1, window - static_cast<int>(std::ceil(reply / dt - 1e-9)) - window / 8);
}

}  // namespace

ControllerService::ControllerService(std::int32_t node_id, std::string expected_run_id)
    : NodeService(node_id, config::NodeSpec::CONTROLLER, std::move(expected_run_id)) {}

runtime::ControllerReport ControllerService::report() const {
  return answers_ ? answers_->exchange().report() : runtime::ControllerReport{};
}

int ControllerService::configure(const runtime::Assign& assign) {
  if (!assign.node().has_controller())
    throw std::invalid_argument("a CONTROLLER node needs its `controller` link");
  const config::ControllerLink& link = assign.node().controller();
  const config::Deployment& deployment = assign.study().deployment();
  const runtime::AnswerWindow answers = runtime::answer_window(deployment, assign.dt());
  runtime::check_controller_link(link, answers, assign.actuators_size(), "");
  ExchangeSettings settings;
  settings.actuators = assign.actuators_size();
  settings.dt = assign.dt();
  settings.real_time = deployment.clock() == config::Deployment::REAL_TIME;
  settings.reply_timeout = runtime::controller_reply_timeout(link, answers);
  settings.lost_window =
      settings.real_time ? lost_window(deployment, assign.dt(), settings.reply_timeout) : 1;
  settings.max_drift = 2.0 * deployment.limits().max_displacement();
  settings.max_force = link.max_force();
  settings.max_measured_rate = link.max_measured_rate() > 0
                                   ? link.max_measured_rate()
                                   : 2.0 * deployment.limits().max_velocity();
  settings.max_force_rate = link.max_force_rate();
  settings.max_tracking_error = link.max_tracking_error();
  settings.tracking_error_steps = link.tracking_error_steps() > 0 ? link.tracking_error_steps() : 3;
  settings.jump_floor = runtime::controller_jump_floor(link);
  settings.tracking_lag = runtime::controller_expected_lag(link);
  settings.hold_time = runtime::controller_hold_time(link);
  answers_ = std::make_unique<ControllerAnswers>(
      std::make_unique<ControllerExchange>(link, settings), label());
  spdlog::info(
      "{}: UDP {} -> controller {}, frames of {} and {} bytes, reply timeout {} ms, hold time {} "
      "ms",
      label(), link.local_address() + ":" + std::to_string(link.local_port()),
      answers_->exchange().peer(), frame_size(link.command()), frame_size(link.feedback()),
      settings.reply_timeout * 1e3, settings.hold_time * 1e3);
  spdlog::info("{}: {}", label(), runtime::controller_checks_text(link, deployment, assign.dt()));
  return settings.actuators;
}

void ControllerService::fill_heartbeat(runtime::Heartbeat& heartbeat) const {
  if (!answers_) return;
  *heartbeat.mutable_controller() = answers_->exchange().report();
  if (!heartbeat.final()) return;
  runtime::NodeRejects node;
  node.set_label(label());
  *node.mutable_controller() = heartbeat.controller();
  spdlog::info("{}", runtime::controller_link_text(node));
}

}  // namespace rths::controller_node
