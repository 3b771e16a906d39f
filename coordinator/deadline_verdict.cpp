#include "coordinator/deadline_verdict.h"

namespace rths::coordinator {
namespace {

double percent(std::uint64_t part, std::uint64_t whole) {
  return 100.0 * static_cast<double>(part) / static_cast<double>(whole);
}

bool beyond(std::uint64_t overruns, std::uint64_t whole, double tolerance) {
  return tolerance >= 0 && whole > 0 &&
         static_cast<double>(overruns) > tolerance * static_cast<double>(whole);
}

}  // namespace

std::optional<std::string> servo_deadline_misses(const std::string& node, std::uint64_t overruns,
                                                 std::uint64_t periods, double tolerance) {
  if (!beyond(overruns, periods, tolerance)) return std::nullopt;
  return "completed with deadline misses: the servo loop of " + node + " overran " +
         std::to_string(overruns) + " of " + std::to_string(periods) + " periods (" +
         std::to_string(percent(overruns, periods)) + " %, tolerance " +
         std::to_string(100.0 * tolerance) + " %)";
}

}  // namespace rths::coordinator
