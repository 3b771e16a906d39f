#include "identify/residual/robust.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace rths::identify {

double median_of(std::vector<double> x) {
  if (x.empty()) return 0.0;
  const auto mid = x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2);
  std::nth_element(x.begin(), mid, x.end());
  return *mid;
}

double robust_sigma(const std::vector<double>& x, double centre) {
  std::vector<double> deviation(x.size());
  for (std::size_t j = 0; j < x.size(); ++j) deviation[j] = std::abs(x[j] - centre);
  return 1.4826 * median_of(std::move(deviation));
}

}  // namespace rths::identify
