#include "runtime/rt/pacing.h"

#include <gtest/gtest.h>

#include <vector>

namespace rths::runtime {
namespace {

constexpr double kPeriod = 0.001;  // s
constexpr std::int64_t kPeriodNs = 1'000'000;

// Time moves only when the code under test sleeps, or when the test says work took time.
class FakeClock final : public PacingClock {
 public:
  std::int64_t now_ns() override { return now_; }
  void sleep_until_ns(std::int64_t deadline) override {
    sleeps.push_back(deadline);
    if (deadline > now_) now_ = deadline + wake_latency;
  }
  void work(std::int64_t ns) { now_ += ns; }
  std::int64_t wake_latency = 0;
  std::vector<std::int64_t> sleeps;

 private:
  std::int64_t now_ = 5'000'000'000;
};

TEST(Pacer, SleepsToAbsoluteDeadlinesThatDoNotDrift) {
  FakeClock clock;
  Pacer pacer(clock, kPeriod);
  pacer.start();
  const std::int64_t start = clock.now_ns();
  for (int k = 1; k <= 5; ++k) {
    clock.work(300'000);  // 0.3 ms of work each step
    const PaceResult r = pacer.wait(k);
    EXPECT_FALSE(r.overrun);
    EXPECT_DOUBLE_EQ(r.lateness, 0.0);
  }
  ASSERT_EQ(clock.sleeps.size(), 5u);
  for (int k = 1; k <= 5; ++k) EXPECT_EQ(clock.sleeps[k - 1], start + k * kPeriodNs);
  EXPECT_EQ(pacer.overruns(), 0u);
}

TEST(Pacer, LateStepIsCountedAndTheGridIsKept) {
  FakeClock clock;
  Pacer pacer(clock, kPeriod);
  pacer.start();
  const std::int64_t start = clock.now_ns();
  pacer.wait(1);
  clock.work(1'500'000);  // step 1 takes 1.5 ms: past deadline 2
  const PaceResult late = pacer.wait(2);
  EXPECT_TRUE(late.overrun);
  EXPECT_NEAR(late.lateness, 0.0005, 1e-12);
  const PaceResult next = pacer.wait(3);  // back on the grid, not re-based
  EXPECT_FALSE(next.overrun);
  EXPECT_EQ(clock.sleeps.back(), start + 3 * kPeriodNs);
  EXPECT_EQ(pacer.overruns(), 1u);
  EXPECT_NEAR(pacer.max_lateness(), 0.0005, 1e-12);
}

TEST(Pacer, WakeUpLatencyIsReportedAsLateness) {
  FakeClock clock;
  clock.wake_latency = 20'000;  // the OS wakes us 20 us late
  Pacer pacer(clock, kPeriod);
  pacer.start();
  const PaceResult r = pacer.wait(1);
  EXPECT_FALSE(r.overrun);
  EXPECT_NEAR(r.lateness, 20e-6, 1e-12);
}

TEST(Pacer, RejectsNonPositivePeriod) {
  FakeClock clock;
  EXPECT_THROW(Pacer(clock, 0.0), std::invalid_argument);
}

TEST(MonotonicClock, SleepsUntilAnAbsoluteDeadline) {
  MonotonicClock clock;
  const std::int64_t deadline = clock.now_ns() + 2'000'000;
  clock.sleep_until_ns(deadline);
  EXPECT_GE(clock.now_ns(), deadline);
}

}  // namespace
}  // namespace rths::runtime
