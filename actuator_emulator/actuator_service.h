#pragma once
// Actuator emulator: hosts the experimental storeys' actuators (core::Actuator: the case's delay
// chain in simulated time, then the emulated specimen). Input: Command.drift and drift_velocity,
// one per hosted actuator, and Command.time (s). Output: Feedback.realised (m) and Feedback.force
// (N, measured), same order.
//
// Faults (the contract a lab relies on; HOLD = ignore every later command and bring each actuator
// to rest at the position the specimen had when the hold began, as a servo controller's interlock
// does: the servo's target ramps there from where it was at the rate limit,
// deployment.limits.max_displacement_step per command period, never in a jump (no rate limit: at
// the largest change between two commands the run has sent, so a hold is never faster than the
// test). The emulator plays this ramp in simulated time once the HOLD has been reported (on_settle,
// so it never delays the report) and logs it; hold_settles() has it.):
//   HOLD from the coordinator                         -> hold at once (the next command is
//                                                        ignored).
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
#include "runtime/node/node_service.h"

namespace rths::actuator_emulator {

class ActuatorService final : public runtime::NodeService {
 public:
  ActuatorService(std::int32_t node_id, std::string expected_run_id);
  // Where actuator `index` is held (m): the realised drift when the hold began.
  double held_position(int index) const {
    return hold_settles_.empty() ? realised_.at(index) : hold_settles_.at(index).position;
  }

  // How one actuator came to rest after a hold (all SI: m, s).
  struct HoldSettle {
    double from = 0.0;                   // the servo's target when the hold began
    double position = 0.0;               // the hold position (realised drift when the hold began)
    double max_change = 0.0;             // the ramp's limit per servo period
    int ramp_ticks = 0;                  // servo periods until the target reached the hold position
    double largest_target_change = 0.0;  // per servo period, over the ramp (<= max_change)
    double largest_realised_change = 0.0;  // per servo period, until rest
    double realised = 0.0;                 // at rest (or when the settle gave up)
    double settle_time = 0.0;  // s of simulated time until |realised - position| <= 1 um
    bool settled = false;      // within 1 um of the hold position within kMaxSettleTime
  };
  static constexpr double kMaxSettleTime = 2.0;  // s
  const std::vector<HoldSettle>& hold_settles() const { return hold_settles_; }

 protected:
  int configure(const runtime::Assign& assign) override;
  void compute(const runtime::Command& command, runtime::Feedback& feedback) override;
  std::string refusal(const runtime::Command& command) override;
  double servo_period() const override { return servo_period_; }
  void load(const runtime::Command& command) override;
  void tick(runtime::Feedback& feedback) override;
  void on_hold() override;
  void on_settle() override;

 private:
  std::vector<core::Actuator> actuators_;
  std::vector<double> realised_;
  std::vector<HoldSettle> hold_settles_;
  std::vector<double> previous_drift_;          // m, the newest command's drift
  std::vector<double> largest_command_change_;  // m, largest |drift change| between two commands
  bool commanded_ = false;
  void note_command(const runtime::Command& command);
  std::vector<double> last_command_;    // m, drift of the previous accepted command
  double max_displacement_step_ = 0.0;  // m per command; 0 = no rate limit
  double dt_ = 0.0;                     // s, the integrator step
  double servo_period_ = 0.0;  // s; > 0 only in real time with a servo faster than the integrator
  void require_sizes(const runtime::Command& command) const;
};

}  // namespace rths::actuator_emulator
