#pragma once
// The cause a node gives (runtime.proto Hold.reason) when its command watchdog holds it: no fresh
// command for its limit. NodeLoop writes it, followed by how long and the limit in ms; the
// coordinator tells by it the HOLD a run held from the view expects (no command leaves then) from
// a node's fault (its limits, its controller, a refused command), which ends any run.

#include <string_view>

namespace rths::runtime {

inline constexpr std::string_view kCommandWatchdogCause = "command watchdog: no fresh command for ";

// Whether `reason` (a node's Hold.reason) is its command watchdog's.
inline bool is_command_watchdog_hold(std::string_view reason) {
  return reason.starts_with(kCommandWatchdogCause);
}

}  // namespace rths::runtime
