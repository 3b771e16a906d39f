#include "runtime/node/lag.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/metrics.h"
#include "study/case_link.h"

namespace rths::runtime {

LagInjector::LagInjector(const config::LinkLag& spec, double dt)
    : lag_(study::link_way(spec), dt) {}

LagSummary summarize(std::vector<double> lags) {
  LagSummary s;
  s.count = lags.size();
  if (lags.empty()) return s;
  std::sort(lags.begin(), lags.end());
  s.mean = std::accumulate(lags.begin(), lags.end(), 0.0) / static_cast<double>(lags.size());
  s.median = core::median(lags);  // the one median (mean of the middle two when even)
  s.p99 = lags[std::min(lags.size() - 1, static_cast<std::size_t>(0.99 * lags.size()))];
  s.max = lags.back();
  return s;
}

}  // namespace rths::runtime
