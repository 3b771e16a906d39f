// coordinator/answer_wait: a real-time step stops waiting for answers that do not come within
// the wait, and waits again once they come well within it.
#include "coordinator/answer_wait.h"

#include <gtest/gtest.h>

#include <cstddef>

namespace rths::coordinator {
namespace {

constexpr double kWait = 122e-6;  // s: half a 4096 Hz period

// Feeds `n` answers of round trip `r`; the answer count at the first switch (0: none), into it.
std::size_t feed(AnswerWait& w, std::size_t n, double r, AnswerWait::Switch* out = nullptr) {
  for (std::size_t i = 1; i <= n; ++i)
    if (const auto s = w.step(r)) {
      if (out) *out = *s;
      return i;
    }
  return 0;
}

TEST(AnswerWait, AnswersWithinTheWaitAreWaitedFor) {
  AnswerWait w(kWait);
  EXPECT_EQ(feed(w, 10000, 60e-6), 0u);
  EXPECT_TRUE(w.waiting());
}

TEST(AnswerWait, AnswersSlowerThanTheWaitStopTheWaitAtTheFirstJudgement) {
  AnswerWait w(kWait);
  AnswerWait::Switch s;
  EXPECT_EQ(feed(w, 10000, 170e-6, &s), AnswerWait::kJudged);
  EXPECT_FALSE(s.waiting);
  EXPECT_DOUBLE_EQ(s.median_round_trip, 170e-6);
  EXPECT_FALSE(w.waiting());
}

TEST(AnswerWait, TheMedianDecidesNotTheOutliers) {
  AnswerWait few_late(kWait), most_late(kWait);
  for (std::size_t i = 0; i < AnswerWait::kJudged; ++i) {
    few_late.step(i % 4 == 0 ? 5e-3 : 50e-6);   // a quarter stalled
    most_late.step(i % 4 == 0 ? 50e-6 : 5e-3);  // three quarters late
  }
  EXPECT_TRUE(few_late.waiting());
  EXPECT_FALSE(most_late.waiting());
}

TEST(AnswerWait, ARoundTripBetweenAQuarterOfTheWaitAndTheWaitKeepsTheStateItFinds) {
  AnswerWait w(kWait);
  ASSERT_GT(feed(w, 1000, 200e-6), 0u);
  ASSERT_FALSE(w.waiting());
  EXPECT_EQ(feed(w, 20000, 0.3 * kWait), 0u);  // as fast as answers come while nobody waits
  EXPECT_EQ(feed(w, 20000, 0.9 * kWait), 0u);
  EXPECT_FALSE(w.waiting());
}

TEST(AnswerWait, FastAnswersAreWaitedForAgainOnlyAfterTheSettlingAnswers) {
  AnswerWait w(kWait);
  ASSERT_GT(feed(w, 1000, 200e-6), 0u);
  AnswerWait::Switch s;
  EXPECT_EQ(feed(w, 10000, 25e-6, &s), AnswerWait::kSettle);
  EXPECT_TRUE(s.waiting);
  EXPECT_DOUBLE_EQ(s.median_round_trip, 25e-6);
  EXPECT_TRUE(w.waiting());
  // Each later switch waits twice as long as the one before: a round trip that keeps changing
  // switches a handful of times in a run, not every second.
  EXPECT_EQ(feed(w, 10000, 200e-6), 2 * AnswerWait::kSettle);
  EXPECT_EQ(feed(w, 10000, 25e-6), 4 * AnswerWait::kSettle);
}

}  // namespace
}  // namespace rths::coordinator
