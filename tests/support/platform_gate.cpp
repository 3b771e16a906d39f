#include "tests/support/platform_gate.h"

#include <cstdio>

#include "rt_check/check.h"

namespace rths::test {

MeasuredPlatform measure_platform(double rate_hz, double seconds) {
  const std::vector<int> cpus = rt_check::allowed_cpus();
  const rt_check::LatencyStats stats(rt_check::measure_wakeups(cpus, rate_hz, seconds));
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

}  // namespace rths::test
