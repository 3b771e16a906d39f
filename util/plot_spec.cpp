#include "util/plot_spec.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rths::util {

std::optional<std::pair<double, double>> padded_y_range(const std::vector<Series>& series,
                                                        const std::vector<std::size_t>& include,
                                                        double margin) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < series.size(); ++i) {
    if (!include.empty() && std::find(include.begin(), include.end(), i) == include.end()) continue;
    for (double y : series[i].y) {
      if (!std::isfinite(y)) continue;
      lo = std::min(lo, y);
      hi = std::max(hi, y);
    }
  }
  if (!(lo <= hi)) return std::nullopt;
  const double pad = std::max(hi - lo, std::abs(hi) * 1e-9 + 1e-300) * margin;
  return std::make_pair(lo - pad, hi + pad);
}

}  // namespace rths::util
