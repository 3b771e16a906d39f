#include "actuator_emulator/actuator_service.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "runtime/node/plan.h"

namespace rths::actuator_emulator {

ActuatorService::ActuatorService(std::int32_t node_id, std::string expected_run_id)
    : NodeService(node_id, config::NodeSpec::ACTUATOR_EMULATOR, std::move(expected_run_id)) {}

int ActuatorService::configure(const runtime::Assign& assign) {
  const config::Case& study_case = study::find_case(assign.study(), assign.case_name());
  core::HybridSetup setup =
      runtime::setup_without_motion(assign.study(), assign.base_dir(), assign.dt(), study_case);
  const std::vector<int> hosted(assign.actuators().begin(), assign.actuators().end());
  study::apply_compensation(setup, hosted, assign.node().compensation(),
                            "deployment.nodes[id " + std::to_string(assign.node().id()) + "]");
  actuators_.clear();
  for (int a : assign.actuators()) {
    if (a < 0 || a >= static_cast<int>(setup.delays.size()))
      throw std::invalid_argument("actuator " + std::to_string(a) + " does not exist");
    actuators_.push_back(core::make_actuator(setup.partition, a, setup.delays.at(a), setup.dt,
                                             setup.servo_substeps));
  }
  const bool real_time = assign.study().deployment().clock() == config::Deployment::REAL_TIME;
  servo_period_ = real_time && setup.servo_substeps > 1 ? setup.dt / setup.servo_substeps : 0.0;
  dt_ = setup.dt;
  realised_.assign(actuators_.size(), 0.0);
  last_command_.assign(actuators_.size(), 0.0);
  previous_drift_.assign(actuators_.size(), 0.0);
  largest_command_change_.assign(actuators_.size(), 0.0);
  commanded_ = false;
  max_displacement_step_ = assign.study().deployment().limits().max_displacement_step();
  return static_cast<int>(actuators_.size());
}

std::string ActuatorService::refusal(const runtime::Command& command) {
  if (!(max_displacement_step_ > 0)) return {};
  const int n = std::min<int>(command.drift_size(), static_cast<int>(last_command_.size()));
  for (int i = 0; i < n; ++i) {
    const double change = command.drift(i) - last_command_[i];
    if (!(std::abs(change) <= max_displacement_step_))
      return "commanded drift of actuator " + std::to_string(i + 1) + " changes by " +
             std::to_string(change) + " m in one command (rate limit " +
             std::to_string(max_displacement_step_) + " m per command)";
  }
  for (int i = 0; i < n; ++i) last_command_[i] = command.drift(i);
  return {};
}

void ActuatorService::require_sizes(const runtime::Command& command) const {
  const int n = static_cast<int>(actuators_.size());
  if (command.drift_size() != n || command.drift_velocity_size() != n)
    throw std::invalid_argument(label() + ": command has " + std::to_string(command.drift_size()) +
                                " drifts for " + std::to_string(n) + " actuators");
}

void ActuatorService::note_command(const runtime::Command& command) {
  for (std::size_t i = 0; i < actuators_.size(); ++i) {
    const double drift = command.drift(static_cast<int>(i));
    if (commanded_)
      largest_command_change_[i] =
          std::max(largest_command_change_[i], std::abs(drift - previous_drift_[i]));
    previous_drift_[i] = drift;
  }
  commanded_ = true;
}

void ActuatorService::load(const runtime::Command& command) {
  require_sizes(command);
  note_command(command);
  for (int i = 0; i < static_cast<int>(actuators_.size()); ++i)
    actuators_[i].command({command.time(), command.drift(i), command.drift_velocity(i)});
}

void ActuatorService::tick(runtime::Feedback& feedback) {
  for (std::size_t i = 0; i < actuators_.size(); ++i) {
    const core::ActuatorOutput out = actuators_[i].tick();
    realised_[i] = out.realised;
    feedback.add_realised(out.realised);
    feedback.add_force(out.force);
  }
}

void ActuatorService::on_hold() {
  hold_settles_.assign(actuators_.size(), HoldSettle{});
  for (std::size_t i = 0; i < actuators_.size(); ++i) {
    core::Actuator& actuator = actuators_[i];
    HoldSettle& h = hold_settles_[i];
    h.from = actuator.target_displacement();
    h.position = realised_[i];
    const int substeps = actuator.servo_substeps();
    const double span = std::abs(h.from - h.position);
    const double per_command =
        max_displacement_step_ > 0 ? max_displacement_step_ : largest_command_change_[i];
    h.max_change = per_command > 0 ? per_command / substeps : (span > 0 ? span / substeps : 1.0);
    actuator.hold(h.position, h.max_change);
  }
}

void ActuatorService::on_settle() {
  for (std::size_t i = 0; i < actuators_.size(); ++i) {
    core::Actuator& actuator = actuators_[i];
    HoldSettle& h = hold_settles_.at(i);
    const double period = servo_period_ > 0 ? servo_period_ : dt_ / actuator.servo_substeps();
    const int max_ticks = static_cast<int>(kMaxSettleTime / period);
    double target = h.from, realised = realised_[i];
    for (int tick = 1; tick <= max_ticks; ++tick) {
      const core::ActuatorOutput out = actuator.tick();
      const double now_target = actuator.target_displacement();
      if (h.ramp_ticks == 0) {
        h.largest_target_change = std::max(h.largest_target_change, std::abs(now_target - target));
        if (actuator.hold_reached()) h.ramp_ticks = tick;
      }
      h.largest_realised_change =
          std::max(h.largest_realised_change, std::abs(out.realised - realised));
      target = now_target;
      realised = out.realised;
      if (h.ramp_ticks > 0 && std::abs(realised - h.position) <= 1e-6) {
        h.settled = true;
        h.settle_time = tick * period;
        break;
      }
    }
    h.realised = realised;
    realised_[i] = realised;
    spdlog::warn(
        "{}: actuator {} held: target ramped from {:.6f} m to {:.6f} m at <= {:.6f} m per "
        "servo period in {} periods; realised {:.6f} m{}",
        label(), i + 1, h.from, h.position, h.max_change, h.ramp_ticks, realised,
        h.settled ? " at rest after " + std::to_string(h.settle_time) + " s"
                  : " (not within 1 um of the hold position after " +
                        std::to_string(kMaxSettleTime) + " s)");
  }
}

void ActuatorService::compute(const runtime::Command& command, runtime::Feedback& feedback) {
  require_sizes(command);
  note_command(command);
  const int n = static_cast<int>(actuators_.size());
  for (int i = 0; i < n; ++i) {
    const core::ActuatorOutput out =
        actuators_[i].step({command.time(), command.drift(i), command.drift_velocity(i)});
    realised_[i] = out.realised;
    feedback.add_realised(out.realised);
    feedback.add_force(out.force);
  }
}

}  // namespace rths::actuator_emulator
