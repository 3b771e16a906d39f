#include "runtime/node/lag.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/metrics.h"
#include "study/study.h"

namespace rths::runtime {

LagInjector::LagInjector(const config::LinkLag& spec, double dt)
    : spec_(spec), dt_(dt), rng_(spec.seed()) {}

bool LagInjector::active() const {
  const config::NetworkEmulation& net = spec_.network();
  return spec_.one_way_delay() > 0 || spec_.jitter() > 0 || spec_.loss() > 0 ||
         net.drift_rate() > 0 || (net.spike_delay() > 0 && net.spike_every() > 0) ||
         net.drop_steps() > 0;
}

std::optional<double> LagInjector::emulated_extra(std::int64_t step) const {
  const config::NetworkEmulation& net = spec_.network();
  if (step < 0) return 0.0;
  if (step >= net.drop_first_step() &&
      step < std::int64_t{net.drop_first_step()} + net.drop_steps())
    return std::nullopt;
  double extra = net.drift_rate() * static_cast<double>(step) * dt_;
  if (net.spike_every() > 0 && step % net.spike_every() < net.spike_steps())
    extra += net.spike_delay();
  return extra;
}

std::optional<std::int64_t> LagInjector::schedule(std::int64_t arrival_ns,
                                                  std::int64_t command_step) {
  if (spec_.loss() > 0 && uniform_(rng_) < spec_.loss()) return std::nullopt;
  double delay = spec_.one_way_delay();
  if (spec_.jitter() > 0) delay = std::max(0.0, delay + spec_.jitter() * normal_(rng_));
  const std::optional<double> extra = emulated_extra(command_step);
  if (!extra) return std::nullopt;
  const std::int64_t release = std::max(
      arrival_ns + static_cast<std::int64_t>(std::llround((delay + *extra) * 1e9)), last_release_);
  last_release_ = release;
  last_delay_ = std::max(0.0, static_cast<double>(release - arrival_ns) * 1e-9 - *extra);
  return release;
}

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
