// The servo loop's deadline verdict: beyond the tolerance says so with the figures; within it or
// with no servo periods says nothing. The integrator loop's verdict is runtime::deadline_verdict
// (tests/runtime/realtime_verdict_test.cpp).
#include "coordinator/deadline_verdict.h"

#include <gtest/gtest.h>

namespace rths::coordinator {
namespace {

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
