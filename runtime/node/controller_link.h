#pragma once
// The controller block of a CONTROLLER node (config::ControllerLink) checked one way, wherever a
// study is read: `rths run`, `launch`, `sites`, the coordinator (through make_plan) and the
// controller node itself, so that every command refuses the same block with the same message.
//
//   check_frame_layout(layout, actuators, direction, where) -> throws std::invalid_argument
//     naming the field: exactly one COUNTER (i32 or u32); at most one STATUS (integer) and
//     COMMAND_TIME; every actuator in [0, actuators) has exactly one field of each role the
//     direction needs (command: TARGET_DISPLACEMENT; feedback: MEASURED_DISPLACEMENT and
//     MEASURED_FORCE) and at most one of the others; roles of the other direction refused;
//     scale finite and not negative.
//   controller_reply_timeout(link, window) -> s: reply_timeout_ms, or its default (the
//     lockstep 1 s, or half the real-time answer window), never longer than the window within
//     which an answer may still be applied.
//   controller_hold_time(link) -> s: hold_time_ms in [0, 60000], 0 = 500 ms.
//   controller_jump_floor(link) -> m: the measured-jump check's floor, jump_floor (0 = 0.2 mm;
//     < 0: the check is off, returned as 0).
//   controller_expected_lag(link) -> s: expected_lag_ms (0 = 50 ms), the adaptive tracking
//     bound's lag.
//   check_controller_link(link, window, actuators, where): both layouts, each frame at
//     most kMaxControllerFrameBytes, IPv4 addresses and ports 1-65535, the timings above and the
//     plausibility limits finite and >= 0.

#include <cstddef>
#include <string>

#include "rths/proto/deployment.pb.h"

namespace rths::runtime {

enum class FrameDirection { kCommand, kFeedback };

inline constexpr std::size_t kMaxControllerFrameBytes = 2048;  // the most of a datagram read

// Within what an answer may still be applied (runtime/node/plan.h answer_window() makes it from
// a deployment): in real time `steps` steps of dt, in lockstep the step_timeout.
struct AnswerWindow {
  bool real_time = false;
  double dt = 0.0;            // s
  int steps = 0;              // real time: max_missed_answers
  double step_timeout = 0.0;  // s, lockstep
  double seconds() const { return real_time ? steps * dt : step_timeout; }
};

std::size_t frame_field_size(config::FrameField::Type type);  // bytes
std::size_t frame_size(const config::FrameLayout& layout);    // bytes
// Roles with a value per actuator (targets, measurements), and those of each direction.
bool per_actuator_role(config::FrameField::Role role);
bool command_role(config::FrameField::Role role);
bool feedback_role(config::FrameField::Role role);

void check_frame_layout(const config::FrameLayout& layout, int actuators, FrameDirection direction,
                        const std::string& where);
double controller_reply_timeout(const config::ControllerLink& link, const AnswerWindow& window);
double controller_hold_time(const config::ControllerLink& link);
double controller_jump_floor(const config::ControllerLink& link);
double controller_expected_lag(const config::ControllerLink& link);
void check_controller_link(const config::ControllerLink& link, const AnswerWindow& window,
                           int actuators, const std::string& where);

}  // namespace rths::runtime
