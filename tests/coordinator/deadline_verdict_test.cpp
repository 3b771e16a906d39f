// Deadline verdicts: beyond the tolerance says so with the figures; within it, at it, with no
// steps or with the check off (-1) says nothing.
#include "coordinator/deadline_verdict.h"

#include <gtest/gtest.h>

namespace rths::coordinator {
namespace {

TEST(DeadlineVerdict, LoopBeyondTheToleranceNamesOverrunsStepsAndStreak) {
  const auto v = loop_deadline_misses(12, 3, 10000, 0.001);
  ASSERT_TRUE(v.has_value());
  EXPECT_EQ(*v,
            "completed with deadline misses: 12 overruns in 10000 steps (0.120000 %, "
            "tolerance 0.100000 %; worst streak 3)");
}

TEST(DeadlineVerdict, LoopWithinAtOrUnjudgedSaysNothing) {
  EXPECT_FALSE(loop_deadline_misses(10, 1, 10000, 0.001).has_value()) << "at the tolerance";
  EXPECT_FALSE(loop_deadline_misses(5, 1, 10000, 0.001).has_value());
  EXPECT_FALSE(loop_deadline_misses(9999, 50, 10000, -1).has_value()) << "-1 turns it off";
  EXPECT_FALSE(loop_deadline_misses(0, 0, 0, 0.0).has_value()) << "no steps";
  EXPECT_TRUE(loop_deadline_misses(1, 1, 10000, 0.0).has_value()) << "0 tolerates none";
}

TEST(DeadlineVerdict, ServoLoopBeyondTheToleranceNamesTheNode) {
  const auto v = servo_deadline_misses("node 2 (actuator emulator)", 50, 40000, 0.001);
  ASSERT_TRUE(v.has_value());
  EXPECT_EQ(*v,
            "completed with deadline misses: the servo loop of node 2 (actuator emulator) "
            "overran 50 of 40000 periods (0.125000 %, tolerance 0.100000 %)");
  EXPECT_FALSE(servo_deadline_misses("n", 40, 40000, 0.001).has_value());
  EXPECT_FALSE(servo_deadline_misses("n", 0, 0, 0.001).has_value()) << "no servo loop ran";
}

}  // namespace
}  // namespace rths::coordinator
