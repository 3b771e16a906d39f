#include "identify/run/clock_offset.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/metrics.h"

namespace rths::identify {
namespace {

double median_less(const std::vector<double>& x, double injected) {
  std::vector<double> y;
  y.reserve(x.size());
  for (double v : x)
    if (std::isfinite(v)) y.push_back(v - injected);
  return y.empty() ? 0.0 : core::median(y);
}

std::string ms(double seconds) {
  std::ostringstream out;
  out << std::showpos << std::setprecision(3) << seconds * 1e3 << " ms";
  return out.str();
}

}  // namespace

std::optional<ClockOffset> clock_offset(const std::vector<double>& down,
                                        const std::vector<double>& up, double injected_down,
                                        double injected_up) {
  const std::size_t n = std::min(down.size(), up.size());
  if (n < kMinClockSamples) return std::nullopt;
  ClockOffset c;
  c.samples = n;
  c.down_median = median_less(down, injected_down);
  c.up_median = median_less(up, injected_up);
  c.offset = 0.5 * (c.down_median - c.up_median);
  const bool negative = std::min(c.down_median, c.up_median) < -kNegativeTolerance;
  c.named = std::abs(c.offset) > kMinClockOffset || negative;
  c.detail = "node clock - coordinator clock " + ms(c.offset) + " (one-way medians, injection " +
             "removed: down " + ms(c.down_median) + ", up " + ms(c.up_median) + ", " +
             std::to_string(n) + " answers" +
             (negative ? "; a negative one-way time needs an offset" : "") +
             "; a path slower one way than the other looks the same: synchronise the hosts' "
             "clocks (PTP, chrony) before reading one-way lags)";
  return c;
}

}  // namespace rths::identify
