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
  return fmt::format(
      "; meanwhile {} unauthenticated messages ({:.0f} a second) were dropped unread ({}{}): a "
      "flood on the run's DDS domain took receive time from the loop",
      total, rate, each, newest.empty() ? "" : "; newest: " + newest);
}

}  // namespace rths::coordinator
