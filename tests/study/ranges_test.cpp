#include "study/ranges.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rths::study {
namespace {

std::string message_of(Quantity quantity, double value, const std::string& name) {
  try {
    check_range(quantity, value, name);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Ranges, StepIsOneMicrosecondToOneSecond) {
  EXPECT_EQ(check_range(Quantity::kStep, 1e-6, "--dt"), 1e-6);
  EXPECT_EQ(check_range(Quantity::kStep, 1.0, "--dt"), 1.0);
  EXPECT_EQ(message_of(Quantity::kStep, 1e-9, "--dt"),
            "--dt = 1e-09 s is outside [1e-06, 1] s (an integration or sampling step)");
  EXPECT_THROW(check_range(Quantity::kStep, 1.5, "--dt"), std::invalid_argument);
}

TEST(Ranges, PeriodExcludesZeroAndStopsAtFifty) {
  EXPECT_NE(message_of(Quantity::kPeriod, 0.0, "--period").find("(0, 50] s"), std::string::npos);
  EXPECT_THROW(check_range(Quantity::kPeriod, 1e300, "--period"), std::invalid_argument);
  EXPECT_EQ(check_range(Quantity::kPeriod, 50.0, "--period"), 50.0);
}

TEST(Ranges, LagOverOneSecondNamesTheUnitSlipAndAllowLongLag) {
  const std::string message = message_of(Quantity::kLag, 7.0, "nodes[1].send_lag.one_way_delay");
  EXPECT_NE(message.find("nodes[1].send_lag.one_way_delay = 7 s is outside [0, 1] s"),
            std::string::npos);
  EXPECT_NE(message.find("allow_long_lag"), std::string::npos);
  EXPECT_EQ(check_lag(7.0, "x", true), 7.0);
  EXPECT_THROW(check_lag(7.0, "x"), std::invalid_argument);
  EXPECT_THROW(check_lag(-0.001, "x", true), std::invalid_argument);
}

TEST(Ranges, CountsAreWholeAndAtLeastOne) {
  EXPECT_EQ(check_range(Quantity::kCount, 3LL, "max_missed_answers"), 3);
  EXPECT_THROW(check_range(Quantity::kCount, -3LL, "max_missed_answers"), std::invalid_argument);
  EXPECT_THROW(check_range(Quantity::kCount, 0LL, "--folds"), std::invalid_argument);
  EXPECT_THROW(check_range(Quantity::kCount, 2.5, "--folds"), std::invalid_argument);
}

TEST(Ranges, CpuMustExistOnThisMachine) {
  const Range cpus = range_of(Quantity::kCpu);
  EXPECT_EQ(check_range(Quantity::kCpu, 0LL, "loop_cpu"), 0);
  EXPECT_THROW(check_range(Quantity::kCpu, static_cast<long long>(cpus.max) + 1, "loop_cpu"),
               std::invalid_argument);
  EXPECT_THROW(check_range(Quantity::kCpu, -1LL, "loop_cpu"), std::invalid_argument);
}

TEST(Ranges, FifoPrioritiesLeaveTheKernelsOwnToIt) {
  EXPECT_EQ(check_range(Quantity::kFifoPriority, 80LL, "realtime_priority"), 80);
  EXPECT_THROW(check_range(Quantity::kFifoPriority, 99LL, "realtime_priority"),
               std::invalid_argument);
  EXPECT_THROW(check_range(Quantity::kFifoPriority, -5LL, "realtime_priority"),
               std::invalid_argument);
}

TEST(Ranges, TimeoutsArePositive) {
  EXPECT_THROW(check_range(Quantity::kTimeout, -1.0, "--timeout"), std::invalid_argument);
  EXPECT_THROW(check_range(Quantity::kTimeout, 0.0, "--timeout"), std::invalid_argument);
  EXPECT_EQ(check_range(Quantity::kTimeout, 30.0, "--timeout"), 30.0);
}

TEST(Ranges, NothingNonFiniteIsInside) {
  for (Quantity q : {Quantity::kLag, Quantity::kStep, Quantity::kFraction, Quantity::kTimeout}) {
    EXPECT_FALSE(range_of(q).contains(std::numeric_limits<double>::quiet_NaN()));
    EXPECT_FALSE(range_of(q).contains(std::numeric_limits<double>::infinity()));
  }
}

TEST(Ranges, FractionsAndRatiosAreZeroToOne) {
  EXPECT_EQ(range_of(Quantity::kFraction).text(), "[0, 1]");
  EXPECT_EQ(range_of(Quantity::kDampingRatio).text(), "[0, 1]");
  EXPECT_TRUE(range_violation(Quantity::kFraction, 0.99, "x").empty());
  EXPECT_FALSE(range_violation(Quantity::kFraction, 1.01, "x").empty());
}

}  // namespace
}  // namespace rths::study
