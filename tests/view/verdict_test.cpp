// The badge of a finished run: a real-time run is shown by the one real-time verdict, in the
// coordinator's words; one that overran within it is a warning, never a calm "completed".
#include "view/verdict.h"

#include <gtest/gtest.h>

namespace rths::view {
namespace {

// A real-time run of 10,000 commanded steps under the default rule (0.1 %, 3 steps in a row).
FinishedRun real_time(std::uint64_t overruns, std::uint64_t streak, bool ok = true,
                      const std::string& status = "completed") {
  FinishedRun run;
  run.footer.set_ok(ok);
  run.footer.set_status(status);
  run.real_time = true;
  run.counts = {10000, overruns, streak};
  return run;
}

TEST(ShownVerdict, ARunWithoutOverrunsIsCompleted) {
  const ShownVerdict v = shown_verdict(real_time(0, 0));
  EXPECT_EQ(v.state, "completed");
  EXPECT_EQ(v.level, "ok");
  EXPECT_EQ(v.badge, "completed");
  EXPECT_EQ(v.text, "");
}

TEST(ShownVerdict, OverrunsWithinTheVerdictAreAWarningWithTheirShareAndStreak) {
  const ShownVerdict v = shown_verdict(real_time(7, 2));
  EXPECT_EQ(v.state, "completed");
  EXPECT_EQ(v.level, "warning");
  EXPECT_EQ(v.badge, "completed with 7 overruns");
  EXPECT_EQ(v.text,
            "7 overruns in 10000 steps (0.07 %), within the tolerance of 0.1 % "
            "(max_overrun_fraction); worst streak 2 steps, within the fail-safe's window of 3; "
            "each late step is marked in the record");
  FinishedRun off = real_time(2626, 3);
  off.rule.max_fraction = -1;
  EXPECT_NE(shown_verdict(off).text.find("26.3 %), the overrun tolerance is off"),
            std::string::npos)
      << shown_verdict(off).text;
}

TEST(ShownVerdict, ARunPastTheVerdictIsFailedInTheCoordinatorsWords) {
  const ShownVerdict v = shown_verdict(real_time(2626, 2));  // a footer of an older coordinator
  EXPECT_EQ(v.state, "failed");
  EXPECT_EQ(v.level, "failed");
  EXPECT_EQ(v.badge, "completed with deadline misses");
  EXPECT_EQ(v.text, *runtime::deadline_verdict({10000, 2626, 2}, {}));
  const ShownVerdict servo = shown_verdict(
      real_time(0, 0, false, "completed with deadline misses: the servo loop of node 2 overran"));
  EXPECT_EQ(servo.state, "failed");
  EXPECT_EQ(servo.badge, "completed with deadline misses");
  EXPECT_EQ(servo.text, "completed with deadline misses: the servo loop of node 2 overran");
}

TEST(ShownVerdict, AStoppedOrDivergedRunIsFailedWithItsStatus) {
  const ShownVerdict stopped = shown_verdict(real_time(0, 0, false, "stopped from the view"));
  EXPECT_EQ(stopped.state, "stopped");
  EXPECT_EQ(stopped.level, "failed");
  EXPECT_EQ(stopped.badge, "stopped");
  EXPECT_EQ(stopped.text, "stopped from the view");
  FinishedRun diverged = real_time(0, 0, false, "diverged");
  diverged.footer.set_diverged(true);
  EXPECT_EQ(shown_verdict(diverged).badge, "diverged");
  EXPECT_EQ(shown_verdict(diverged).state, "stopped");
}

// `rths launch` judged the case against the lag-free run: a case whose coordinator completed
// every step but whose response grows is shown as launch's table shows it, red when launch fails
// on it; the record's own deadline verdict still comes first.
TEST(ShownVerdict, HowLaunchJudgedTheCaseIsShownWhenItIsNotCompleted) {
  FinishedRun run = real_time(0, 0);
  run.judged = JudgedCase{"diverging", "past its critical delay and its envelope grows", true};
  ShownVerdict v = shown_verdict(run);
  EXPECT_EQ(v.state, "completed");
  EXPECT_EQ(v.level, "failed");
  EXPECT_EQ(v.badge, "diverging");
  EXPECT_EQ(v.text, "past its critical delay and its envelope grows");
  run.judged = JudgedCase{"diverged (expected)", "peak 40 mm", false};
  EXPECT_EQ(shown_verdict(run).level, "warning");
  EXPECT_EQ(shown_verdict(run).badge, "diverged (expected)");
  run.judged = JudgedCase{"completed", "", false};
  EXPECT_EQ(shown_verdict(run).badge, "completed");
  FinishedRun late = real_time(2626, 2);
  late.judged = JudgedCase{"diverging", "", true};
  EXPECT_EQ(shown_verdict(late).badge, "completed with deadline misses");
}

TEST(ShownVerdict, APlatformRefusedAndRunAnywayIsAWarning) {
  FinishedRun run = real_time(0, 0);
  run.platform_overridden = true;
  run.platform_verdict = "stalls of 6 ms need a 14 ms window";
  const ShownVerdict v = shown_verdict(run);
  EXPECT_EQ(v.level, "warning");
  EXPECT_EQ(v.badge, "completed on a refused platform");
  EXPECT_NE(v.text.find("--accept-platform): stalls of 6 ms"), std::string::npos) << v.text;
}

TEST(ShownVerdict, ALockstepRunIsNeverJudgedOnDeadlines) {
  FinishedRun run = real_time(5000, 5000);
  run.real_time = false;
  EXPECT_EQ(shown_verdict(run).level, "ok");
  EXPECT_EQ(shown_verdict(run).badge, "completed");
}

}  // namespace
}  // namespace rths::view
