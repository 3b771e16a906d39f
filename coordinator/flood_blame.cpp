#include "coordinator/flood_blame.h"

#include <fmt/format.h>

namespace rths::coordinator {

std::optional<std::string> unauthenticated_flood(
    const std::vector<std::pair<std::string, std::uint64_t>>& receivers, double wall_seconds,
    const std::string& newest) {
  std::uint64_t total = 0;
  std::string each;
  for (const auto& [label, count] : receivers) {
    if (count == 0) continue;
    total += count;
    each += (each.empty() ? "" : ", ") + label + " " + std::to_string(count);
  }
  if (total == 0) return std::nullopt;
  const double rate = wall_seconds > 0 ? static_cast<double>(total) / wall_seconds : 0.0;
  const double threshold = kFloodShare / kDropSeconds;  // messages a second
  const std::string dropped = fmt::format(
      "; meanwhile {} unauthenticated messages ({:.0f} a second) were dropped unread "
      "({}{}): ",
      total, rate, each, newest.empty() ? "" : "; newest: " + newest);
  // Without a wall time the rate is unknown: a count that large in any run is a flood.
  const bool flood = wall_seconds > 0 ? rate >= threshold
                                      : static_cast<double>(total) * kDropSeconds >= kFloodShare;
  if (flood)
    return dropped + fmt::format(
                         "a flood on the run's DDS domain took receive time from the loop (a "
                         "flood from {:.0f} a second: {:g} % of the run's time at {:g} us a "
                         "message)",
                         threshold, 100 * kFloodShare, kDropSeconds * 1e6);
  return dropped + fmt::format(
                       "too few to take the loop's time (about {:.3g} ms of receive work in the "
                       "run's {:.3g} s, under {:g} %; a flood from {:.0f} a second), not the cause",
                       static_cast<double>(total) * kDropSeconds * 1e3, wall_seconds,
                       100 * kFloodShare, threshold);
}

}  // namespace rths::coordinator
