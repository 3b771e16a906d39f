// The one real-time verdict (runtime/record/realtime_verdict.h) on hand-made counts: each of its
// three rules fails a run on its own, a negative tolerance turns off the fraction rule and never
// the streak or the dominating share, and a run within all three (or with no steps) passes.
#include "runtime/record/realtime_verdict.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace rths::runtime {
namespace {

using testing::HasSubstr;

constexpr DeadlineRule kRule{0.001, 12};  // paper_frame_distributed at 1 ms: 12 ms window

TEST(RealTimeVerdict, OverrunsBeyondTheToleranceNameOverrunsStepsAndStreak) {
  const DeadlineCounts c{10000, 12, 3};
  EXPECT_EQ(deadline_breach(c, kRule), DeadlineBreach::kFraction);
  EXPECT_EQ(deadline_verdict(c, kRule),
            "completed with deadline misses: 12 overruns in 10000 steps (0.120000 %, "
            "tolerance 0.100000 %; worst streak 3)");
}

TEST(RealTimeVerdict, WithinOrAtTheToleranceOrWithoutStepsPasses) {
  EXPECT_FALSE(deadline_verdict({10000, 10, 1}, kRule)) << "at the tolerance";
  EXPECT_FALSE(deadline_verdict({10000, 5, 1}, kRule));
  EXPECT_FALSE(deadline_verdict({10000, 10, 12}, kRule)) << "a streak at the window";
  EXPECT_FALSE(deadline_verdict({0, 0, 0}, kRule)) << "no steps";
  EXPECT_TRUE(deadline_verdict({10000, 1, 1}, {0.0, 12})) << "0 tolerates none";
}

// The researcher's run: 2,626 overruns, 1,279 of them in a row, under a tolerance relaxed to
// 5 % (or turned off). Its fraction passed; its streak is 100 times the fail-safe's window.
TEST(RealTimeVerdict, AStreakBeyondTheFailSafesWindowFailsWhateverTheTolerance) {
  const DeadlineCounts c{61440, 2626, 1279};
  for (const double tolerance : {0.05, -1.0}) {
    const DeadlineRule rule{tolerance, 12};
    EXPECT_EQ(deadline_breach(c, rule), DeadlineBreach::kStreak) << tolerance;
    const auto v = deadline_verdict(c, rule);
    ASSERT_TRUE(v) << tolerance;
    EXPECT_EQ(v->rfind("completed with deadline misses: 1279 steps in a row overran, more than "
                       "the fail-safe's window of 12 (2626 overruns in 61440 steps, ",
                       0),
              0u)
        << *v;
    EXPECT_THAT(*v, HasSubstr("not a real-time test's"));
  }
  EXPECT_FALSE(deadline_verdict({61440, 40, 12}, {-1.0, 12})) << "isolated, tolerance off";
}

TEST(RealTimeVerdict, MoreThanHalfTheStepsOverrunFailsWhateverTheTolerance) {
  const DeadlineCounts c{1000, 501, 1};  // every other step, never two in a row
  for (const double tolerance : {1.0, -1.0}) {
    EXPECT_EQ(deadline_breach(c, {tolerance, 12}), DeadlineBreach::kDominated) << tolerance;
    EXPECT_THAT(deadline_verdict(c, {tolerance, 12}).value_or(""),
                HasSubstr("more than half; worst streak 1): the response shows the platform"));
  }
  EXPECT_FALSE(deadline_verdict({1000, 500, 1}, {1.0, 12})) << "half is not more than half";
}

// The deployment's rule: max_overrun_fraction (0 = 0.001) and the answer window in steps, the
// one the fail-safe uses (ms rounded up to whole steps, else max_missed_answers, else 3).
TEST(RealTimeVerdict, TheRuleIsTheDeploymentsToleranceAndFailSafeWindow) {
  config::Deployment d;
  EXPECT_EQ(deadline_rule(d, 1e-3).max_fraction, 0.001);
  EXPECT_EQ(deadline_rule(d, 1e-3).max_streak, 3u);
  d.set_max_overrun_fraction(-1);
  d.set_answer_window_ms(12);
  EXPECT_EQ(deadline_rule(d, 1e-3).max_fraction, -1.0);
  EXPECT_EQ(deadline_rule(d, 1e-3).max_streak, 12u);
  EXPECT_EQ(deadline_rule(d, 1.0 / 4096).max_streak, 50u);  // 12 ms at 4096 Hz: 49.2 -> 50
}

}  // namespace
}  // namespace rths::runtime
