#include "runtime/rt/wait_policy.h"

#include <gtest/gtest.h>

#include <vector>

#include "runtime/rt/pacing.h"

namespace rths::runtime {
namespace {

constexpr std::int64_t kStart = 1'000'000'000;
constexpr std::int64_t kDeadline = kStart + 1'000'000;  // 1 ms ahead
constexpr std::int64_t kReadCostNs = 1'000;             // each clock read advances time 1 us

// Reading the clock costs time (so a spin ends); sleeping lands `oversleep` late.
class FakeClock final : public PacingClock {
 public:
  std::int64_t now_ns() override {
    ++reads;
    const std::int64_t t = now;
    now += kReadCostNs;
    return t;
  }
  void sleep_until_ns(std::int64_t deadline) override {
    sleeps.push_back(deadline);
    if (deadline > now) now = deadline + oversleep;
  }
  std::int64_t now = kStart;
  std::int64_t oversleep = 0;
  int reads = 0;
  std::vector<std::int64_t> sleeps;
};

TEST(WaitPolicy, SleepSleepsOnceToTheDeadlineAndCarriesTheTimersLateness) {
  FakeClock clock;
  clock.oversleep = 80'000;
  wait_until(clock, kDeadline, {WaitPolicyKind::kSleep});
  ASSERT_EQ(clock.sleeps, std::vector<std::int64_t>{kDeadline});
  EXPECT_EQ(clock.now, kDeadline + 80'000);
}

TEST(WaitPolicy, SleepThenSpinSleepsToTheMarginThenSpinsOntoTheDeadline) {
  FakeClock clock;
  clock.oversleep = 80'000;  // less than the margin: the spin absorbs it
  wait_until(clock, kDeadline, {WaitPolicyKind::kSleepThenSpin, 200'000});
  ASSERT_EQ(clock.sleeps, std::vector<std::int64_t>{kDeadline - 200'000});
  EXPECT_GE(clock.now, kDeadline);
  EXPECT_LE(clock.now, kDeadline + 2 * kReadCostNs);  // no later than one clock read past it
  EXPECT_GT(clock.reads, 100);                        // it did spin for ~120 us of reads
}

TEST(WaitPolicy, SleepThenSpinInsideTheMarginDoesNotSleep) {
  FakeClock clock;
  clock.now = kDeadline - 50'000;
  wait_until(clock, kDeadline, {WaitPolicyKind::kSleepThenSpin, 200'000});
  EXPECT_TRUE(clock.sleeps.empty());
  EXPECT_GE(clock.now, kDeadline);
}

TEST(WaitPolicy, SpinNeverSleeps) {
  FakeClock clock;
  wait_until(clock, kDeadline, {WaitPolicyKind::kSpin});
  EXPECT_TRUE(clock.sleeps.empty());
  EXPECT_GE(clock.now, kDeadline);
  EXPECT_LE(clock.now, kDeadline + 2 * kReadCostNs);
}

TEST(WaitPolicy, APassedDeadlineReturnsAtOnceForEveryPolicy) {
  for (WaitPolicyKind kind :
       {WaitPolicyKind::kSleep, WaitPolicyKind::kSleepThenSpin, WaitPolicyKind::kSpin}) {
    FakeClock clock;
    clock.now = kDeadline + 5'000;
    wait_until(clock, kDeadline, {kind, 200'000});
    EXPECT_TRUE(clock.sleeps.empty()) << to_string(kind);
    EXPECT_LE(clock.reads, 2) << to_string(kind);
  }
}

TEST(WaitPolicy, PacerUsesItsPolicy) {
  FakeClock clock;
  clock.oversleep = 80'000;
  Pacer pacer(clock, 0.001, {WaitPolicyKind::kSleepThenSpin, 200'000});
  pacer.start();
  const PaceResult r = pacer.wait(1);
  EXPECT_FALSE(r.overrun);
  EXPECT_LT(r.lateness, 5e-6);  // the timer's 80 us lateness is gone
}

}  // namespace
}  // namespace rths::runtime
