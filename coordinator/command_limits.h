#pragma once
// CommandLimits: the coordinator's safety limits on what it commands, checked before a command
// leaves (deployment.limits; a limit of 0 is off).
//   check_state(u, v)  per DOF: |u_i| <= max_displacement (m) and |v_i| <= max_velocity (m/s).
//   check_rate(drift)  per actuator storey s: |drift_s - previous_s| <= max_displacement_step
//                      (m per step), previous = the drift last passed (0 before the first); the
//                      drift becomes the previous one only when it passes.
// Each returns the violation, worded for the run's status ("safety limit: ...; command not
// sent"), or nothing. A NaN never passes. No allocation when a check passes.

#include <optional>
#include <string>
#include <vector>

#include "core/structure.h"
#include "rths/proto/deployment.pb.h"

namespace rths::coordinator {

class CommandLimits {
 public:
  // storeys: the size of a drift vector; actuator_storeys index into it.
  CommandLimits(const config::SafetyLimits& limits, std::vector<int> actuator_storeys, int storeys);
  std::optional<std::string> check_state(const core::Vec& u, const core::Vec& v) const;
  std::optional<std::string> check_rate(const core::Vec& drift);

 private:
  config::SafetyLimits limits_;
  std::vector<int> actuator_storeys_;
  core::Vec previous_;  // m, per storey
};

}  // namespace rths::coordinator
