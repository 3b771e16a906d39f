#include "study/ranges.h"

#include <unistd.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "study/text_columns.h"

namespace rths::study {
namespace {

double configured_cpus() {
  const long cpus = sysconf(_SC_NPROCESSORS_CONF);
  return cpus > 0 ? static_cast<double>(cpus) : 1.0;
}

std::string with_unit(const std::string& text, std::string_view unit) {
  return unit.empty() ? text : text + " " + std::string(unit);
}

}  // namespace

bool Range::contains(double value) const {
  if (!std::isfinite(value)) return false;
  if (integer && value != std::floor(value)) return false;
  const bool above_min = min_open ? value > min : value >= min;
  const bool below_max = max_open ? value < max : value <= max;
  return above_min && below_max;
}

std::string Range::text() const {
  return with_unit(
      std::string(min_open ? "(" : "[") + core::format_number(min) + ", " +
          (integer ? std::to_string(static_cast<long long>(max)) : core::format_number(max)) +
          (max_open ? ")" : "]"),
      unit);
}

Range range_of(Quantity quantity) {
  constexpr double kIntMax = std::numeric_limits<int>::max();
  switch (quantity) {
    case Quantity::kLag: return {0, 1, false, false, "s", "an actuator or network lag"};
    case Quantity::kLongLag: return {0, 3600, false, false, "s", "a lag with allow_long_lag"};
    case Quantity::kStep: return {1e-6, 1, false, false, "s", "an integration or sampling step"};
    case Quantity::kPeriod: return {0, 50, true, false, "s", "a natural period"};
    case Quantity::kDampingRatio: return {0, 1, false, false, "", "a damping ratio, 0.05 = 5 %"};
    case Quantity::kFraction: return {0, 1, false, false, "", "a fraction"};
    case Quantity::kCount: return {1, kIntMax, false, false, "", "a count", true};
    case Quantity::kTimeout: return {0, 86400, true, false, "s", "a timeout"};
    case Quantity::kCpu:
      return {0, configured_cpus() - 1, false, false, "", "a CPU of this machine", true};
    case Quantity::kMotionScale: return {0, 100, false, false, "", "a factor on the motion"};
    case Quantity::kDdsDomain: return {0, 232, false, false, "", "a DDS domain id", true};
    case Quantity::kDays: return {1, 36500, false, false, "d", "a validity in days", true};
    case Quantity::kFrequency: return {0, 1e7, true, false, "Hz", "a rate"};
    case Quantity::kFifoPriority:
      return {1, 98, false, false, "", "a SCHED_FIFO priority below the kernel's 99", true};
  }
  throw std::logic_error("range_of: unknown quantity");
}

std::string range_violation(Quantity quantity, double value, std::string_view name) {
  const Range range = range_of(quantity);
  if (range.contains(value)) return "";
  std::string message = (name.empty() ? "" : std::string(name) + " = ") +
                        with_unit(core::format_number(value), range.unit) + " is outside " +
                        range.text() + " (" + std::string(range.what) + ")";
  if (quantity == Quantity::kLag && value > range.max) {
    message +=
        "; lags are in seconds (14 ms is 0.014); allow_long_lag: true in the study allows "
        "up to " +
        core::format_number(range_of(Quantity::kLongLag).max) + " s";
  }
  return message;
}

double check_range(Quantity quantity, double value, std::string_view name) {
  const std::string message = range_violation(quantity, value, name);
  if (!message.empty()) throw std::invalid_argument(message);
  return value;
}

int check_range(Quantity quantity, long long value, std::string_view name) {
  const std::string message = range_violation(quantity, static_cast<double>(value), name);
  if (!message.empty()) throw std::invalid_argument(message);
  return static_cast<int>(value);
}

double check_lag(double seconds, std::string_view name, bool allow_long_lag) {
  return check_range(allow_long_lag ? Quantity::kLongLag : Quantity::kLag, seconds, name);
}

}  // namespace rths::study
