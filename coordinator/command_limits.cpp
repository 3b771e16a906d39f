#include "coordinator/command_limits.h"

#include <cmath>

namespace rths::coordinator {

CommandLimits::CommandLimits(const config::SafetyLimits& limits, std::vector<int> actuator_storeys,
                             int storeys)
    : limits_(limits),
      actuator_storeys_(std::move(actuator_storeys)),
      previous_(core::Vec::Zero(storeys)) {}

std::optional<std::string> CommandLimits::check_state(const core::Vec& u,
                                                      const core::Vec& v) const {
  for (int i = 0; i < u.size(); ++i) {
    if (limits_.max_displacement() > 0 && !(std::abs(u[i]) <= limits_.max_displacement()))
      return "safety limit: |u| of DOF " + std::to_string(i + 1) + " = " + std::to_string(u[i]) +
             " m exceeds " + std::to_string(limits_.max_displacement()) + " m; command not sent";
    if (limits_.max_velocity() > 0 && !(std::abs(v[i]) <= limits_.max_velocity()))
      return "safety limit: |v| of DOF " + std::to_string(i + 1) + " = " + std::to_string(v[i]) +
             " m/s exceeds " + std::to_string(limits_.max_velocity()) + " m/s; command not sent";
  }
  return std::nullopt;
}

std::optional<std::string> CommandLimits::check_rate(const core::Vec& drift) {
  const double limit = limits_.max_displacement_step();
  if (limit > 0)
    for (int s : actuator_storeys_) {
      const double change = drift[s] - previous_[s];
      if (!(std::abs(change) <= limit))
        return "safety limit: commanded drift of storey " + std::to_string(s + 1) + " changes by " +
               std::to_string(change) + " m in one step (limit " + std::to_string(limit) +
               " m per step); command not sent";
    }
  previous_ = drift;
  return std::nullopt;
}

}  // namespace rths::coordinator
