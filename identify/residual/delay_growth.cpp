#include "identify/residual/delay_growth.h"

#include "core/metrics.h"

#include <cmath>
#include <vector>

namespace rths::identify {
std::optional<DelayGrowth> delay_growth(std::span<const double> time,
                                        std::span<const double> residual,
                                        std::span<const double> prediction, double dt) {
  const std::size_t n = residual.size();
  if (n < 3 || prediction.size() != n || time.size() != n || !(dt > 0.0)) return std::nullopt;
  const double mid = 0.5 * (time.front() + time.back());
  std::vector<double> rate(n), growing(n);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t lo = j == 0 ? 0 : j - 1, hi = j + 1 == n ? j : j + 1;
    rate[j] = (prediction[hi] - prediction[lo]) / (static_cast<double>(hi - lo) * dt);
    growing[j] = rate[j] * (time[j] - mid);
  }
  const double mr = core::mean(residual), ma = core::mean(rate), mg = core::mean(growing);
  double aa = 0.0, gg = 0.0, ag = 0.0, ra = 0.0, rg = 0.0, rr = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    const double a = rate[j] - ma, g = growing[j] - mg, y = residual[j] - mr;
    aa += a * a;
    gg += g * g;
    ag += a * g;
    ra += y * a;
    rg += y * g;
    rr += y * y;
  }
  const double det = aa * gg - ag * ag;
  if (!(det > 0.0) || !(rr > 0.0)) return std::nullopt;
  const double ca = (ra * gg - rg * ag) / det, cg = (rg * aa - ra * ag) / det;
  const double left = std::max(0.0, rr - ca * ra - cg * rg);
  const double variance = left / static_cast<double>(n - 3);
  DelayGrowth out{-cg, std::sqrt(variance * aa / det), -ca, 1.0 - left / rr};
  if (std::abs(out.growth) < kGrowthSigmas * out.growth_error ||
      out.explained < kMinGrowthExplained)
    return std::nullopt;
  return out;
}

}  // namespace rths::identify
