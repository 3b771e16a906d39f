// platform/latency: statistics of wake-up lateness from fixed samples, and a short real
// measurement's shape (never its figures: those belong to `rths rt-check`).
#include "rt_check/latency.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace rths::rt_check {
namespace {

WakeupSamples samples(std::vector<double> lateness, double rate = 1000, double seconds = 1) {
  WakeupSamples s;
  s.cpus = {0};
  s.lateness = {std::move(lateness)};
  s.rate_hz = rate;
  s.seconds = seconds;
  return s;
}

TEST(LatencyStats, QuantilesCountsAndRates) {
  std::vector<double> l(1000, 10e-6);
  l[10] = 1.5e-3;
  l[20] = 2.5e-3;
  l[30] = 6e-3;
  const LatencyStats stats(samples(l));
  EXPECT_EQ(stats.wakeups(), 1000u);
  EXPECT_DOUBLE_EQ(stats.quantile(0.5), 10e-6);
  EXPECT_DOUBLE_EQ(stats.max(), 6e-3);
  EXPECT_DOUBLE_EQ(stats.quantile(0.9999), 6e-3);
  EXPECT_EQ(stats.count_over(1e-3), 3u);
  EXPECT_EQ(stats.count_over(2e-3), 2u);
  EXPECT_EQ(stats.count_over(5e-3), 1u);
  EXPECT_DOUBLE_EQ(stats.minutes(), 1.0 / 60);
  EXPECT_DOUBLE_EQ(stats.stalls_per_minute(2e-3), 120.0);  // 2 in one second
}

TEST(LatencyStats, OverrunsCountEveryDeadlineAStallPasses) {
  // 1 kHz: a wake-up 2.5 ms late ends its step past the next 2 deadlines; with 0.6 ms of work a
  // wake-up 0.5 ms late passes one.
  std::vector<double> l(1000, 0.0);
  l[0] = 2.5e-3;
  l[1] = 0.5e-3;
  const LatencyStats stats(samples(l));
  EXPECT_DOUBLE_EQ(stats.overrun_fraction(0.0), 2.0 / 1000);
  EXPECT_DOUBLE_EQ(stats.overrun_fraction(0.6e-3), 4.0 / 1000);  // 3 (3.1 ms) + 1
}

TEST(LatencyStats, CpusAddTheirMinutes) {
  WakeupSamples s = samples({1e-3, 3e-3});
  s.cpus = {0, 1};
  s.lateness.push_back({3e-3});
  const LatencyStats stats(s);
  EXPECT_EQ(stats.wakeups(), 3u);
  EXPECT_DOUBLE_EQ(stats.minutes(), 2.0 / 60);
  EXPECT_DOUBLE_EQ(stats.stalls_per_minute(2e-3), 60.0);
}

TEST(MeasureWakeups, OneSeriesPerCpuOnTheGrid) {
  const WakeupSamples s = measure_wakeups({0}, 1000, 0.05);
  ASSERT_EQ(s.lateness.size(), 1u);
  EXPECT_GT(s.lateness[0].size(), 0u);
  EXPECT_LE(s.lateness[0].size(), 51u);  // one per deadline at most; stalls skip deadlines
  for (double l : s.lateness[0]) EXPECT_GE(l, 0.0);
}

TEST(MeasureWakeups, ACpuThatCannotBeHadIsNamed) {
  try {
    measure_wakeups({1000}, 1000, 0.01);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("CPU 1000"));
  }
  EXPECT_THROW(measure_wakeups({}, 1000, 0.01), std::invalid_argument);
}

}  // namespace
}  // namespace rths::rt_check
