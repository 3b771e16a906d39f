#pragma once
// A real-time run that failed while its receivers dropped unauthenticated messages says so, and
// says whether they could have been the cause: each dropped message costs its receiver the time
// to read and reject it, and on a shared machine that time is the loop's. Only drops whose rate
// could take a share of the loop's time are called a flood; a handful is named as a handful,
// beside the verdict that states the real cause.
//
// The cost: kDropSeconds a message, measured (docs/security.md, 2026-11-27): a receiver dropping
// forged messages as fast as they came kept up with 0.81 million a second, about 1.2 us each.
// The threshold: the drops' receive work is a flood from kFloodShare (1 %) of the run's wall time,
// kFloodShare / kDropSeconds = 8,333 messages a second (all receivers together, as if on one
// host); 200,000 a second measured no rise in overruns, so every flood that could matter is
// named, and a few messages a second never are.
//
// Inputs   receivers     (label, count) of messages each receiver dropped unread for want of a
//                        valid MAC: the coordinator's own, each node's as of its last heartbeat
//          wall_seconds  s, the run's wall time (the rate's denominator)
//          newest        the newest dropped message as the coordinator named it ("" if none)
// Output   nothing when none was dropped; at or above the threshold "; meanwhile N
//          unauthenticated messages (R a second) were dropped unread (coordinator A, node 2 (...)
//          B; newest: ...): a flood on the run's DDS domain took receive time from the loop (a
//          flood from 8333 a second: 1 % of the run's time at 1.2 us a message)"; below it "...
//          were dropped unread (...): too few to take the loop's time (about W ms of receive work
//          in the run's T s, under 1 %; a flood from 8333 a second), not the cause", to follow
//          the failed status.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rths::coordinator {

inline constexpr double kDropSeconds = 1.2e-6;  // s a receiver spends on one dropped message
inline constexpr double kFloodShare = 0.01;     // of the run's wall time: a flood from here

std::optional<std::string> unauthenticated_flood(
    const std::vector<std::pair<std::string, std::uint64_t>>& receivers, double wall_seconds,
    const std::string& newest);

}  // namespace rths::coordinator
