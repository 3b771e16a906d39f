#include "runtime/node/controller_link.h"

#include <arpa/inet.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <vector>

namespace rths::runtime {
namespace {

using Field = config::FrameField;

constexpr double kDefaultHoldTime = 0.5;       // s
constexpr double kMaxHoldTime = 60.0;          // s
constexpr double kLockstepReplyTimeout = 1.0;  // s
constexpr double kDefaultJumpFloor = 2e-4;     // m, above an f32 mm frame's and a rig's noise
constexpr double kDefaultExpectedLag = 0.05;   // s, a servo-hydraulic rig's lag, with margin

bool integer_type(Field::Type type) { return type == Field::I32 || type == Field::U32; }

void check_field(const Field& f, int actuators, FrameDirection direction,
                 const std::string& where) {
  if (!Field::Role_IsValid(f.role()) || f.role() == Field::ROLE_UNSPECIFIED)
    throw std::invalid_argument(where + ": role not set");
  if (!Field::Type_IsValid(f.type()) || !Field::ByteOrder_IsValid(f.byte_order()))
    throw std::invalid_argument(where + ": type or byte_order unknown");
  if (!std::isfinite(f.scale()) || f.scale() < 0.0)
    throw std::invalid_argument(where + ": scale must be finite and > 0 (0 = 1)");
  const bool wrong_way =
      direction == FrameDirection::kCommand ? feedback_role(f.role()) : command_role(f.role());
  if (wrong_way)
    throw std::invalid_argument(where + ": role " + Field::Role_Name(f.role()) +
                                " belongs to the other direction's frame");
  if ((f.role() == Field::COUNTER || f.role() == Field::STATUS) && !integer_type(f.type()))
    throw std::invalid_argument(where + ": a " + Field::Role_Name(f.role()) +
                                " field is I32 or U32");
  if (per_actuator_role(f.role()) && (f.actuator() < 0 || f.actuator() >= actuators))
    throw std::invalid_argument(where + ": actuator " + std::to_string(f.actuator()) +
                                " is not among the node's " + std::to_string(actuators));
}

// A diagnostic channel is named (the record's column), once, with finite bounds if any.
void check_diagnostic(const Field& f, const std::string& where, std::set<std::string>& names) {
  if (f.name().empty() || !names.insert(f.name()).second)
    throw std::invalid_argument(where + ": a DIAGNOSTIC field needs a name of its own");
  if (!std::isfinite(f.min()) || !std::isfinite(f.max()))
    throw std::invalid_argument(where + ": min and max must be finite");
}

void check_endpoint(const std::string& address, int port, const std::string& where) {
  in_addr parsed{};
  if (inet_pton(AF_INET, address.c_str(), &parsed) != 1)
    throw std::invalid_argument(where + "_address '" + address + "' is not an IPv4 address");
  if (port < 1 || port > 65535)
    throw std::invalid_argument(where + "_port " + std::to_string(port) + " is not in [1, 65535]");
}

void check_limit(double value, const std::string& field) {
  if (!std::isfinite(value) || value < 0)
    throw std::invalid_argument(field + " must be finite and >= 0");
}

}  // namespace

std::size_t frame_field_size(Field::Type type) { return type == Field::F64 ? 8 : 4; }

std::size_t frame_size(const config::FrameLayout& layout) {
  std::size_t n = 0;
  for (const Field& f : layout.fields()) n += frame_field_size(f.type());
  return n;
}

bool per_actuator_role(Field::Role role) {
  return role == Field::TARGET_DISPLACEMENT || role == Field::TARGET_VELOCITY ||
         role == Field::MEASURED_DISPLACEMENT || role == Field::MEASURED_FORCE;
}
bool command_role(Field::Role role) {
  return role == Field::TARGET_DISPLACEMENT || role == Field::TARGET_VELOCITY ||
         role == Field::COMMAND_TIME;
}
bool feedback_role(Field::Role role) {
  return role == Field::MEASURED_DISPLACEMENT || role == Field::MEASURED_FORCE ||
         role == Field::CONTROLLER_EPOCH || role == Field::DIAGNOSTIC;
}

void check_frame_layout(const config::FrameLayout& layout, int actuators, FrameDirection direction,
                        const std::string& where) {
  std::map<std::pair<int, int>, int> seen;  // (role, actuator) -> count
  std::set<std::string> diagnostics;        // their names
  for (int i = 0; i < layout.fields_size(); ++i) {
    const Field& f = layout.fields(i);
    const std::string at = where + ".fields[" + std::to_string(i) + "] (" + f.name() + ")";
    check_field(f, actuators, direction, at);
    if (f.role() == Field::PADDING) continue;
    if (f.role() == Field::DIAGNOSTIC) {
      check_diagnostic(f, at, diagnostics);
      continue;
    }
    const int a = per_actuator_role(f.role()) ? f.actuator() : 0;
    if (++seen[{f.role(), a}] > 1)
      throw std::invalid_argument(at + ": a second " + Field::Role_Name(f.role()) + " field");
  }
  if (!seen.count({Field::COUNTER, 0})) throw std::invalid_argument(where + ": no COUNTER field");
  const std::vector<Field::Role> needed =
      direction == FrameDirection::kCommand
          ? std::vector<Field::Role>{Field::TARGET_DISPLACEMENT}
          : std::vector<Field::Role>{Field::MEASURED_DISPLACEMENT, Field::MEASURED_FORCE};
  for (int a = 0; a < actuators; ++a)
    for (const Field::Role role : needed)
      if (!seen.count({role, a}))
        throw std::invalid_argument(where + ": no " + Field::Role_Name(role) +
                                    " field for actuator " + std::to_string(a));
}

double controller_reply_timeout(const config::ControllerLink& link, const AnswerWindow& answers) {
  const bool real_time = answers.real_time;
  const double window = answers.seconds();
  const double asked = link.reply_timeout_ms() * 1e-3;
  if (!std::isfinite(asked) || asked < 0)
    throw std::invalid_argument("controller.reply_timeout_ms must be finite and >= 0");
  if (asked > window * (1 + 1e-9))
    throw std::invalid_argument(
        "controller.reply_timeout_ms " + fmt::format("{:g}", link.reply_timeout_ms()) +
        " is longer than the " + (real_time ? "answer window" : "lockstep step_timeout") + " (" +
        std::to_string(window * 1e3) +
        " ms): an answer that late could never be applied, and a silent controller would get its "
        "HOLD that late; lower it, or widen the window");
  if (asked > 0) return asked;
  if (!real_time) return std::min(kLockstepReplyTimeout, window);
  return std::max(1, answers.steps / 2) * answers.dt;
}

double controller_hold_time(const config::ControllerLink& link) {
  const double hold = link.hold_time_ms() * 1e-3;
  if (!std::isfinite(hold) || hold < 0 || hold > kMaxHoldTime)
    throw std::invalid_argument("controller.hold_time_ms must be in [0, 60000]");
  return hold > 0 ? hold : kDefaultHoldTime;
}

double controller_jump_floor(const config::ControllerLink& link) {
  if (link.jump_floor() < 0) return 0.0;
  return link.jump_floor() > 0 ? link.jump_floor() : kDefaultJumpFloor;
}

double controller_expected_lag(const config::ControllerLink& link) {
  return link.expected_lag_ms() > 0 ? link.expected_lag_ms() * 1e-3 : kDefaultExpectedLag;
}

void check_controller_link(const config::ControllerLink& link, const AnswerWindow& window,
                           int actuators, const std::string& where) {
  try {
    check_frame_layout(link.command(), actuators, FrameDirection::kCommand, "controller.command");
    check_frame_layout(link.feedback(), actuators, FrameDirection::kFeedback,
                       "controller.feedback");
    for (const auto* layout : {&link.command(), &link.feedback()})
      if (frame_size(*layout) > kMaxControllerFrameBytes)
        throw std::invalid_argument("controller: a frame of " +
                                    std::to_string(frame_size(*layout)) + " bytes (at most " +
                                    std::to_string(kMaxControllerFrameBytes) + ")");
    check_endpoint(link.local_address(), link.local_port(), "controller.local");
    check_endpoint(link.peer_address(), link.peer_port(), "controller.peer");
    controller_reply_timeout(link, window);
    controller_hold_time(link);
    check_limit(link.max_force(), "controller.max_force");
    check_limit(link.max_measured_rate(), "controller.max_measured_rate");
    check_limit(link.max_force_rate(), "controller.max_force_rate");
    check_limit(link.max_tracking_error(), "controller.max_tracking_error");
    check_limit(link.expected_lag_ms(), "controller.expected_lag_ms");
    if (!std::isfinite(link.jump_floor()))
      throw std::invalid_argument("controller.jump_floor must be finite (< 0: off)");
    if (link.tracking_error_steps() < 0)
      throw std::invalid_argument("controller.tracking_error_steps must be >= 0");
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where.empty() ? e.what() : where + ": " + e.what());
  }
}

}  // namespace rths::runtime
