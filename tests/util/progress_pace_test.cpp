// When a long job's progress line is due (util/progress_pace.h): none inside its quiet time, then
// at most one every `every` seconds, by the clock it is given.
#include "util/progress_pace.h"

#include <gtest/gtest.h>

#include <functional>
#include <optional>

namespace rths::util {
namespace {

// A clock the test sets by hand.
struct HandClock {
  double now = 100.0;
  std::function<double()> read() {
    return [this] { return now; };
  }
};

TEST(ProgressPace, NoLineInsideTheQuietTimeThenOneEveryPeriodAtMost) {
  HandClock clock;
  ProgressPace pace({.quiet = 3.0, .every = 5.0, .clock_s = clock.read()});
  clock.now = 102.9;
  EXPECT_FALSE(pace.due());
  EXPECT_FALSE(pace.spoke());
  clock.now = 103.0;
  const std::optional<double> first = pace.due();
  ASSERT_TRUE(first);
  EXPECT_DOUBLE_EQ(*first, 3.0);
  EXPECT_TRUE(pace.spoke());
  clock.now = 107.9;  // 4.9 s after the first line
  EXPECT_FALSE(pace.due());
  clock.now = 108.0;
  const std::optional<double> second = pace.due();
  ASSERT_TRUE(second);
  EXPECT_DOUBLE_EQ(*second, 8.0);
  EXPECT_DOUBLE_EQ(pace.elapsed(), 8.0);
}

TEST(ProgressPace, WithoutQuietTimeOrPeriodEveryAskIsALine) {
  HandClock clock;
  ProgressPace pace({.quiet = 0.0, .every = 0.0, .clock_s = clock.read()});
  for (int i = 0; i < 3; ++i) {
    clock.now += 0.25;
    const std::optional<double> at = pace.due();
    ASSERT_TRUE(at);
    EXPECT_DOUBLE_EQ(*at, 0.25 * (i + 1));
  }
}

}  // namespace
}  // namespace rths::util
