#pragma once
// Actuator emulator: hosts the experimental storeys' actuators (core::Actuator: the case's delay
// chain in simulated time, then the emulated specimen). Input: Command.drift and drift_velocity,
// one per hosted actuator, and Command.time (s). Output: Feedback.realised (m) and Feedback.force
// (N, measured), same order.
//
// Faults (the contract a lab relies on; HOLD = freeze at the last realised position, so the
// specimen sees no jump in position, and ignore every later command):
//   HOLD from the coordinator                         -> hold at once (the next command is ignored).
//   a command whose drift changes by more than        -> hold on its own before acting on it, and
//     deployment.limits.max_displacement_step            answer HOLD (with the reason) instead of
//     from the previous one                              FEEDBACK; the coordinator stops the run.
//   real time: no fresh command for                   -> hold on its own (the node loop's watchdog)
//     deployment.command_watchdog_periods x dt           within one more loop wake-up, and send
//     (default 3)                                        HOLD with the reason to the coordinator.
//   the coordinator silent for the orphan timeout     -> leave (exit 1), already holding.
//
// Servo loop (study.servo.rate, an integer multiple N of the integrator's rate): each actuator runs
// N servo periods of dt / N per integrator step and ramps each command (core::Actuator). Lockstep:
// a command runs its N periods in simulated time and is answered once (equal to in process, bit
// for bit). Real time with N > 1: commands only load the ramp; the node loop paces the servo
// periods on the clock and each one streams a FEEDBACK (servo_sample, sampled_ns) for the newest
// command. Ticks and overruns go up in the heartbeat.

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
  std::string refusal(const runtime::Command& command) override;
  double servo_period() const override { return servo_period_; }
  void load(const runtime::Command& command) override;
  void tick(runtime::Feedback& feedback) override;

 private:
  std::vector<core::Actuator> actuators_;
  std::vector<double> realised_;
  std::vector<double> last_command_;    // m, drift of the previous accepted command
  double max_displacement_step_ = 0.0;  // m per command; 0 = no rate limit
  double servo_period_ = 0.0;  // s; > 0 only in real time with a servo faster than the integrator
  void require_sizes(const runtime::Command& command) const;
};

}  // namespace rths::actuator_emulator
