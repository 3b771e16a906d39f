#include "rt_check/latency.h"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>

#include "rt_check/probe.h"
#include "runtime/rt/pacing.h"

namespace rths::rt_check {
namespace {

void pin_to(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (const int err = pthread_setaffinity_np(pthread_self(), sizeof set, &set); err != 0)
    throw std::runtime_error("measuring on CPU " + std::to_string(cpu) + ": " + std::strerror(err));
}

// Until `end_ns`, or until `stop` is set where one is given.
void sample(double rate_hz, std::int64_t start_ns, std::int64_t end_ns,
            const std::atomic<bool>* stop, std::vector<double>& out) {
  runtime::MonotonicClock clock;
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  const double period_ns = 1e9 / rate_hz;
  for (std::int64_t k = 1;; ++k) {
    const auto deadline = start_ns + static_cast<std::int64_t>(std::llround(k * period_ns));
    if (deadline > end_ns || (stop != nullptr && stop->load(std::memory_order_relaxed))) return;
    clock.sleep_until_ns(deadline);
    const std::int64_t now = clock.now_ns();
    out.push_back(1e-9 * static_cast<double>(now - deadline));
    // The next deadline still ahead: a stall is one late wake-up, not a run of them.
    k = std::max(k, static_cast<std::int64_t>(std::floor((now - start_ns) / period_ns)));
  }
}

// One pinned thread per CPU from a common start 20 ms ahead (every thread pinned by then).
WakeupSamples measure(const std::vector<int>& cpus, double rate_hz, double seconds,
                      const std::atomic<bool>* stop) {
  WakeupSamples samples;
  samples.cpus = cpus;
  samples.rate_hz = rate_hz;
  samples.lateness.resize(cpus.size());
  if (stop == nullptr)
    for (auto& l : samples.lateness) l.reserve(static_cast<std::size_t>(rate_hz * seconds) + 2);
  DmaLatencyHold dma;
  samples.dma_latency_held = dma.held();
  runtime::MonotonicClock clock;
  const std::int64_t start_ns = clock.now_ns() + 20'000'000;
  const std::int64_t end_ns = start_ns + static_cast<std::int64_t>(seconds * 1e9);
  std::vector<std::string> errors(cpus.size());
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < cpus.size(); ++i)
    threads.emplace_back([&, i] {
      try {
        pin_to(cpus[i]);
        sample(rate_hz, start_ns, end_ns, stop, samples.lateness[i]);
      } catch (const std::exception& e) {
        errors[i] = e.what();
      }
    });
  for (auto& t : threads) t.join();
  for (const std::string& e : errors)
    if (!e.empty()) throw std::runtime_error(e);
  samples.seconds =
      std::max(0.0, 1e-9 * static_cast<double>(std::min(clock.now_ns(), end_ns) - start_ns));
  return samples;
}

}  // namespace

WakeupSamples measure_wakeups(const std::vector<int>& cpus, double rate_hz, double seconds) {
  if (cpus.empty() || !(rate_hz > 0) || !(seconds > 0))
    throw std::invalid_argument("measure_wakeups: needs CPUs, a rate > 0 and seconds > 0");
  WakeupSamples samples = measure(cpus, rate_hz, seconds, nullptr);
  samples.seconds = seconds;
  return samples;
}

WakeupSamples measure_wakeups_until(const std::vector<int>& cpus, double rate_hz,
                                    const std::atomic<bool>& stop, double max_seconds) {
  if (cpus.empty() || !(rate_hz > 0) || !(max_seconds > 0))
    throw std::invalid_argument(
        "measure_wakeups_until: needs CPUs, a rate > 0 and max_seconds > 0");
  return measure(cpus, rate_hz, max_seconds, &stop);
}

LatencyStats::LatencyStats(const WakeupSamples& samples)
    : rate_hz_(samples.rate_hz), seconds_(samples.seconds), cpus_(samples.cpus.size()) {
  for (const auto& l : samples.lateness) sorted_.insert(sorted_.end(), l.begin(), l.end());
  std::sort(sorted_.begin(), sorted_.end());
  minutes_ = samples.seconds * static_cast<double>(cpus_) / 60.0;
}

double LatencyStats::quantile(double q) const {
  if (sorted_.empty()) return 0.0;
  const auto index = static_cast<std::size_t>(std::floor(q * static_cast<double>(sorted_.size())));
  return sorted_[std::min(sorted_.size() - 1, index)];
}

std::uint64_t LatencyStats::count_over(double lateness) const {
  return static_cast<std::uint64_t>(sorted_.end() -
                                    std::upper_bound(sorted_.begin(), sorted_.end(), lateness));
}

double LatencyStats::stalls_per_minute(double lateness) const {
  return minutes_ > 0 ? static_cast<double>(count_over(lateness)) / minutes_ : 0.0;
}

double LatencyStats::overrun_fraction(double work) const {
  const double period = 1.0 / rate_hz_;
  const double deadlines = std::floor(seconds_ * rate_hz_) * static_cast<double>(cpus_);
  if (deadlines <= 0) return 0.0;
  double passed = 0.0;
  // Only wake-ups later than period - work pass a deadline; sorted, so start there.
  for (auto it = std::upper_bound(sorted_.begin(), sorted_.end(), period - work);
       it != sorted_.end(); ++it)
    passed += std::floor((*it + work) / period);
  return passed / deadlines;
}

}  // namespace rths::rt_check
