#include "tests/support/platform_gate.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <thread>
#include <vector>

#include "rt_check/check.h"
#include "runtime/rt/clock.h"

namespace rths::test {

namespace {

MeasuredPlatform summarise(const rt_check::WakeupSamples& samples, double cpu_share) {
  const rt_check::LatencyStats stats(samples);
  const double rate_hz = samples.rate_hz, seconds = samples.seconds;
  const std::vector<int>& cpus = samples.cpus;
  MeasuredPlatform out;
  out.p99 = stats.quantile(0.99);
  out.max = stats.max();
  out.stalls = stats;
  out.cpu_share = cpu_share;
  char text[200];
  std::snprintf(text, sizeof text,
                "wake-up lateness at %.0f Hz over %.1f s on %zu CPUs: p99 %.2f ms, max %.1f ms; "
                "CPU share %.2f",
                rate_hz, seconds, cpus.size(), 1e3 * out.p99, 1e3 * out.max, cpu_share);
  out.text = text;
  std::printf("platform: %s\n", out.text.c_str());
  return out;
}

}  // namespace

double measure_cpu_share(double seconds) {
  using Wall = std::chrono::steady_clock;
  std::vector<double> shares(rt_check::allowed_cpus().size(), 0.0);
  std::vector<std::thread> spinners;
  for (double& share : shares)
    spinners.emplace_back([&share, seconds] {
      const std::int64_t cpu_start = runtime::thread_cpu_ns();
      const auto wall_start = Wall::now();
      const auto until = wall_start + std::chrono::duration_cast<Wall::duration>(
                                          std::chrono::duration<double>(seconds));
      auto now = wall_start;
      while (now < until) now = Wall::now();
      const double cpu = static_cast<double>(runtime::thread_cpu_ns() - cpu_start) * 1e-9;
      share = cpu / std::chrono::duration<double>(now - wall_start).count();
    });
  for (std::thread& spinner : spinners) spinner.join();
  return std::accumulate(shares.begin(), shares.end(), 0.0) / static_cast<double>(shares.size());
}

MeasuredPlatform measure_platform(double rate_hz, double seconds) {
  const double cpu_share = measure_cpu_share(kCpuShareSeconds);
  return summarise(rt_check::measure_wakeups(rt_check::allowed_cpus(), rate_hz, seconds),
                   cpu_share);
}

StallWitness::StallWitness(double rate_hz, double seconds)
    : rate_hz_(rate_hz), seconds_(seconds), before_(measure_platform(rate_hz, seconds)) {}

MeasuredPlatform StallWitness::finish() {
  MeasuredPlatform after = measure_platform(rate_hz_, seconds_);
  MeasuredPlatform& worse = after.max >= before_.max ? after : before_;
  worse.p99 = std::max(before_.p99, after.p99);
  worse.cpu_share = std::min(before_.cpu_share, after.cpu_share);
  worse.text = "before the run " + before_.text + "; after it " + after.text;
  return worse;
}

}  // namespace rths::test
