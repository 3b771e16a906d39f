#pragma once
// Actuator emulator: hosts the experimental storeys' actuators (core::Actuator: the case's delay
// chain in simulated time, then the emulated specimen). Input: Command.drift and drift_velocity,
// one per hosted actuator, and Command.time (s). Output: Feedback.realised (m) and Feedback.force
// (N, measured), same order. On HOLD it stops moving: later commands are ignored.

#include "core/substructure.h"
#include "runtime/node_service.h"

namespace rths::actuator_emulator {

class ActuatorService final : public runtime::NodeService {
 public:
  ActuatorService(std::int32_t node_id, std::string expected_run_id);
  double held_position(int index) const { return realised_.at(index); }

 protected:
  int configure(const runtime::Assign& assign) override;
  void compute(const runtime::Command& command, runtime::Feedback& feedback) override;

 private:
  std::vector<core::Actuator> actuators_;
  std::vector<double> realised_;
};

}  // namespace rths::actuator_emulator
