#include "coordinator/answer_verdict.h"

#include <gtest/gtest.h>

namespace rths::coordinator {
namespace {

TEST(AnswerVerdict, ANodeThatNeverAnsweredFailsTheRun) {
  const auto verdict = answer_shortfall(2, 0, 5000, 0.99);
  ASSERT_TRUE(verdict.has_value());
  EXPECT_EQ(verdict->rfind("failed: node 2 answered 0 of 5000 steps", 0), 0u) << *verdict;
}

TEST(AnswerVerdict, TheFractionIsTheBoundary) {
  EXPECT_FALSE(answer_shortfall(1, 990, 1000, 0.99).has_value());
  EXPECT_TRUE(answer_shortfall(1, 989, 1000, 0.99).has_value());
  EXPECT_FALSE(answer_shortfall(1, 1000, 1000, 1.0).has_value());
  EXPECT_FALSE(answer_shortfall(1, 0, 1000, 0.0).has_value());
}

TEST(AnswerVerdict, NothingToJudgeWithoutSteps) {
  EXPECT_FALSE(answer_shortfall(1, 0, 0, 0.99).has_value());
}

}  // namespace
}  // namespace rths::coordinator
