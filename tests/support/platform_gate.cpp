#include "tests/support/platform_gate.h"

#include <algorithm>
#include <cstdio>

#include "rt_check/check.h"

namespace rths::test {

namespace {

MeasuredPlatform summarise(const rt_check::WakeupSamples& samples) {
  const rt_check::LatencyStats stats(samples);
  const double rate_hz = samples.rate_hz, seconds = samples.seconds;
  const std::vector<int>& cpus = samples.cpus;
  MeasuredPlatform out;
  out.p99 = stats.quantile(0.99);
  out.max = stats.max();
  out.stalls = stats;
  char text[160];
  std::snprintf(text, sizeof text,
                "wake-up lateness at %.0f Hz over %.1f s on %zu CPUs: p99 %.2f ms, max %.1f ms",
                rate_hz, seconds, cpus.size(), 1e3 * out.p99, 1e3 * out.max);
  out.text = text;
  std::printf("platform: %s\n", out.text.c_str());
  return out;
}

}  // namespace

MeasuredPlatform measure_platform(double rate_hz, double seconds) {
  return summarise(rt_check::measure_wakeups(rt_check::allowed_cpus(), rate_hz, seconds));
}

StallWitness::StallWitness(double rate_hz, double seconds)
    : rate_hz_(rate_hz), seconds_(seconds), before_(measure_platform(rate_hz, seconds)) {}

MeasuredPlatform StallWitness::finish() {
  MeasuredPlatform after = measure_platform(rate_hz_, seconds_);
  MeasuredPlatform& worse = after.max >= before_.max ? after : before_;
  worse.p99 = std::max(before_.p99, after.p99);
  worse.text = "before the run " + before_.text + "; after it " + after.text;
  return worse;
}

}  // namespace rths::test
