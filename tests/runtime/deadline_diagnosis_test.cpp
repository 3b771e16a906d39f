// Why a real-time run missed its deadlines, from hand-made steps: each overrun put down to the
// platform (the work fitted, the wake-up came late) or to the loop's own work, the advice that
// follows, and what the record is still good for.
#include "runtime/record/deadline_diagnosis.h"

#include <gtest/gtest.h>

#include <vector>

namespace rths::runtime {
namespace {

constexpr double kDt = 1e-3;

std::vector<StepRecord> steps(std::size_t n) {
  std::vector<StepRecord> out(n);
  for (auto& s : out) s.set_step_wall(0.1e-3);
  return out;
}

std::vector<const StepRecord*> pointers(const std::vector<StepRecord>& s) {
  std::vector<const StepRecord*> out;
  for (const auto& r : s) out.push_back(&r);
  return out;
}

void overrun(StepRecord& s, double wall, double lateness) {
  s.set_overrun(true);
  s.set_step_wall(wall);
  s.set_lateness(lateness);
}

TEST(DeadlineDiagnosis, IsolatedLateWakeUpsArePlatformStallsAndTheRecordIsUsable) {
  auto s = steps(1001);  // the initial row and 1000 commanded steps
  overrun(s[100], 0.1e-3, 3e-3);
  overrun(s[101], 0.1e-3, 2e-3);
  overrun(s[600], 0.2e-3, 1e-3);
  const DeadlineDiagnosis d = diagnose_deadlines(pointers(s), kDt, {0.001, 10});
  EXPECT_EQ(d.overruns, 3u);
  EXPECT_EQ(d.stall_overruns, 3u);
  EXPECT_EQ(d.work_overruns, 0u);
  EXPECT_EQ(d.worst_streak, 2u);
  EXPECT_DOUBLE_EQ(d.worst_lateness, 3e-3);
  EXPECT_EQ(d.cause, "platform stalls");
  ASSERT_FALSE(d.advice.empty());
  EXPECT_NE(d.advice.front().find("rt-check"), std::string::npos);
  EXPECT_EQ(d.usability.rfind("usable as recorded", 0), 0u) << d.usability;
  const std::string text = d.describe();
  EXPECT_NE(text.find("3 of 1000 steps"), std::string::npos) << text;
  EXPECT_NE(text.find("to do:"), std::string::npos) << text;
}

TEST(DeadlineDiagnosis, StepsWhoseOwnWorkOutlastsThePeriodBlameTheLoopAndLongStreaksAreFlagged) {
  auto s = steps(100);
  for (std::size_t k = 10; k < 40; ++k) overrun(s[k], 1.4e-3, 0.5e-3);
  const DeadlineDiagnosis d = diagnose_deadlines(pointers(s), kDt, {0.001, 10});
  EXPECT_EQ(d.work_overruns, 30u);
  EXPECT_EQ(d.cause, "the loop's own work");
  EXPECT_NE(d.advice.front().find("too slow for dt"), std::string::npos);
  EXPECT_EQ(d.usability.rfind("use with care", 0), 0u) << d.usability;
  EXPECT_NE(d.usability.find("not a real-time test's"), std::string::npos) << d.usability;
  // The run's verdict says the same, even with the fraction rule turned off.
  EXPECT_EQ(d.verdict, deadline_verdict({99, 30, 30}, {0.001, 10}));
  const DeadlineDiagnosis off = diagnose_deadlines(pointers(s), kDt, {-1, 10});
  ASSERT_TRUE(off.verdict);
  EXPECT_NE(off.verdict->find("30 steps in a row overran"), std::string::npos) << *off.verdict;
  EXPECT_EQ(off.usability, d.usability);
}

TEST(DeadlineDiagnosis, ARunThatKeptItsDeadlinesHasNoCause) {
  const auto s = steps(10);
  const DeadlineDiagnosis d = diagnose_deadlines(pointers(s), kDt, {0.001, 3});
  EXPECT_EQ(d.cause, "none");
  EXPECT_TRUE(d.advice.empty());
}

// A run stopped by its fail-safe after overruns is told the cause and the fixes as a run that
// completed with deadline misses is; a clean run and a lockstep stop (no overruns) are not.
TEST(DeadlineDiagnosis, AFailSafeStopAfterOverrunsIsDiagnosedToo) {
  EXPECT_TRUE(needs_deadline_diagnosis("completed with deadline misses (2.6 %)", 2600));
  EXPECT_TRUE(
      needs_deadline_diagnosis("no answer for 12 consecutive steps (steps 2591 to 2602)", 1258));
  EXPECT_FALSE(needs_deadline_diagnosis("no answer for 12 consecutive steps", 0));
  EXPECT_FALSE(needs_deadline_diagnosis("completed", 3));
}

// Isolated overruns are still no real-time test when they are most of the steps: a record with
// 59 % of its steps overrun, never two in a row, is dominated by them; 20 % is to be used with
// care, and 3 % is usable, its share stated.
TEST(DeadlineDiagnosis, ARecordIsJudgedByItsShareOfOverrunsAsWellAsByItsStreaks) {
  const auto judged = [](std::size_t every, std::size_t of) {
    auto s = steps(1001);
    for (std::size_t k = 1; k < s.size(); ++k)
      if (k % of < every && k % 2 == 0) overrun(s[k], 0.1e-3, 2e-3);
    return diagnose_deadlines(pointers(s), kDt, {0.001, 10});
  };
  const DeadlineDiagnosis dominated = judged(1, 1);  // every other step: 50 %
  EXPECT_NEAR(dominated.overrun_share(), 0.5, 1e-12);
  EXPECT_EQ(dominated.worst_streak, 1u);
  EXPECT_EQ(dominated.usability.rfind("use with care: 50 %", 0), 0u) << dominated.usability;
  auto s = steps(1001);
  for (std::size_t k = 0; k < 590; ++k) overrun(s[1 + k * 1000 / 590], 0.1e-3, 2e-3);
  const DeadlineDiagnosis most = diagnose_deadlines(pointers(s), kDt, {0.001, 10});
  EXPECT_NEAR(most.overrun_share(), 0.59, 1e-12);
  EXPECT_LE(most.worst_streak, 2u);
  EXPECT_EQ(most.usability.rfind("dominated by overruns: 59 %", 0), 0u) << most.usability;
  const DeadlineDiagnosis few = judged(1, 40);  // one step in 40: 2.5 %
  EXPECT_EQ(few.usability.rfind("usable as recorded", 0), 0u) << few.usability;
  EXPECT_NE(few.usability.find("2.5 % of the steps"), std::string::npos) << few.usability;
}

}  // namespace
}  // namespace rths::runtime
