#pragma once
// A real-time run that failed while its receivers dropped unauthenticated messages says so: a
// flood on the run's DDS domain costs every receiver the time to read and reject each message,
// and on a shared machine that time is the loop's. The flood is named with its rate, so that a
// failed run blames the flood rather than no one.
//
// Inputs   receivers     (label, count) of messages each receiver dropped unread for want of a
//                        valid MAC: the coordinator's own, each node's as of its last heartbeat
//          wall_seconds  s, the run's wall time (the rate's denominator)
//          newest        the newest dropped message as the coordinator named it ("" if none)
// Output   nothing when none was dropped; else "; meanwhile N unauthenticated messages (R a
//          second) were dropped unread (coordinator A, node 2 (...) B; newest: ...): a flood on
//          the run's DDS domain took receive time from the loop", to follow the failed status.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rths::coordinator {

std::optional<std::string> unauthenticated_flood(
    const std::vector<std::pair<std::string, std::uint64_t>>& receivers, double wall_seconds,
    const std::string& newest);

}  // namespace rths::coordinator
