#include "core/envelope_growth.h"

#include "core/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rths::core {

bool EnvelopeGrowth::grows() const {
  return rate > 0.0 && r_squared >= kMinRSquared && rate * span >= std::numbers::ln2;
}

std::optional<EnvelopeGrowth> envelope_growth(std::span<const double> u, double dt, double period) {
  if (!(dt > 0.0)) throw std::invalid_argument("envelope_growth: dt must be > 0");
  if (!(period > 0.0)) throw std::invalid_argument("envelope_growth: period must be > 0");
  const auto window = static_cast<std::size_t>(std::llround(period / dt));
  if (window < 2) return std::nullopt;  // a period of under two samples has no envelope
  const std::size_t whole = u.size() / window;
  const auto share = static_cast<std::size_t>(std::floor(
      EnvelopeGrowth::kFittedShare * static_cast<double>(u.size()) / static_cast<double>(window)));
  const std::size_t windows =
      std::min(whole, std::max<std::size_t>(share, EnvelopeGrowth::kMinWindows));
  if (windows < static_cast<std::size_t>(EnvelopeGrowth::kMinWindows)) return std::nullopt;

  // Window w covers samples [begin, begin + window), the last one ending at the last sample.
  const std::size_t first = u.size() - windows * window;
  std::vector<double> t(windows), y(windows);
  for (std::size_t w = 0; w < windows; ++w) {
    const std::size_t begin = first + w * window;
    double peak = 0.0;
    for (std::size_t k = begin; k < begin + window; ++k) {
      if (!std::isfinite(u[k])) return std::nullopt;
      peak = std::max(peak, std::abs(u[k]));
    }
    if (!(peak > 0.0)) return std::nullopt;
    t[w] = (static_cast<double>(begin) + 0.5 * static_cast<double>(window)) * dt;
    y[w] = std::log(peak);
  }
  const double n = static_cast<double>(windows);
  const double mean_t = mean(t), mean_y = mean(y);
  double stt = 0.0, sty = 0.0, syy = 0.0;
  for (std::size_t w = 0; w < windows; ++w) {
    stt += (t[w] - mean_t) * (t[w] - mean_t);
    sty += (t[w] - mean_t) * (y[w] - mean_y);
    syy += (y[w] - mean_y) * (y[w] - mean_y);
  }
  EnvelopeGrowth g;
  g.windows = static_cast<int>(windows);
  g.period = static_cast<double>(window) * dt;
  g.span = n * g.period;
  g.rate = sty / stt;
  // A flat envelope (syy = 0) is explained by any line: r^2 = 1 with rate 0, which never grows.
  g.r_squared = syy > 0.0 ? (sty * sty) / (stt * syy) : 1.0;
  g.doubling_time =
      g.rate > 0.0 ? std::numbers::ln2 / g.rate : std::numeric_limits<double>::infinity();
  return g;
}

}  // namespace rths::core
