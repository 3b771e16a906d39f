// platform/verdict: the fail-safe window and overrun rules on fixed wake-up statistics.
#include "rt_check/verdict.h"

#include <gmock/gmock.h>
#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace rths::rt_check {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kDt = 1.0 / 1024;

// A minute at 1024 Hz, 50 us late, with `stalls` wake-ups `stall` s late spread over it.
WakeupSamples minute(int stalls, double stall) {
  WakeupSamples s;
  s.cpus = {0};
  s.rate_hz = 1024;
  s.seconds = 60;
  s.lateness.assign(1, std::vector<double>(61440, 50e-6));
  for (int i = 0; i < stalls; ++i) s.lateness[0][static_cast<std::size_t>(i) * 1000] = stall;
  return s;
}

FailSafeInput input(int steps, double run_seconds = 60) {
  FailSafeInput in;
  in.dt = kDt;
  in.run_seconds = run_seconds;
  in.answer_steps = steps;
  in.watchdog_steps = steps;
  in.step_work = 0.05 * kDt;
  in.cpus = {0, 1};
  return in;
}

PlatformFacts stock_vm() {
  PlatformFacts f;
  f.preemption = "PREEMPT_DYNAMIC";
  f.governor = "none (no cpufreq)";
  f.online_cpus = {0, 1};
  return f;
}

// Each finding states its figures to the decimals it promises: steps whole, ms to 2 or 3
// decimals, percentages with a plain % sign.
TEST(Verdict, TheFindingsStateTheirFiguresExactly) {
  const LatencyStats stats(minute(60, 3.5e-3));
  const FailSafeVerdict v = judge_failsafe(stats, stock_vm(), input(3));
  ASSERT_GE(v.findings.size(), 4u);
  EXPECT_THAT(v.findings[0], HasSubstr("windows: the coordinator's answer window 3 steps (2.93 "
                                       "ms); the command watchdog of the actuator emulators and "
                                       "controller nodes 3 periods (2.93 ms)"));
  EXPECT_THAT(v.findings[1], HasSubstr("fail-safe window 2.93 ms (3 steps at 1024 Hz)"));
  EXPECT_THAT(v.findings[2], HasSubstr("required: 8.789 ms (9 steps) for <= 1 % false stops"));
  EXPECT_THAT(v.findings[3], HasSubstr("% of steps against max_overrun_fraction"));
  EXPECT_THAT(v.findings[3], Not(HasSubstr("%%")));
}

TEST(Verdict, AVmStallingOnceASecondRefusesThreeStepsAndNamesTheWindowThatHolds) {
  const LatencyStats stats(minute(60, 3.5e-3));
  const FailSafeVerdict v = judge_failsafe(stats, stock_vm(), input(3));
  EXPECT_FALSE(v.window_holds);
  EXPECT_TRUE(v.refused());
  EXPECT_GT(v.false_stop_probability, 0.99);
  // Fewer than two fit points: stalls are assumed up to twice the longest (7 ms), plus a step.
  EXPECT_EQ(v.required_steps, 9);
  EXPECT_DOUBLE_EQ(v.required_window_ms, 8.789);  // 9 steps, the window the run will use
  char window[64];
  std::snprintf(window, sizeof window, "answer_window_ms: %.3f", v.required_window_ms);
  EXPECT_THAT(v.refusal(), HasSubstr(window));
  // A stall at the fault's moment delays the HOLD by as much: the bound says so.
  EXPECT_THAT(v.refusal(), HasSubstr("plus any stall at that moment: up to 3.50 ms measured here"));
  EXPECT_THAT(v.refusal(), HasSubstr("does NOT hold"));
  EXPECT_THAT(v.refusal(), HasSubstr("PREEMPT_RT"));
  EXPECT_THAT(v.refusal(), HasSubstr("pin_loop: true loop_cpu: 1"));
  EXPECT_TRUE(judge_failsafe(stats, stock_vm(), input(9)).window_holds);
  EXPECT_FALSE(judge_failsafe(stats, stock_vm(), input(8)).window_holds);
}

TEST(Verdict, OverrunsAreJudgedAgainstTheTolerance) {
  const LatencyStats stats(minute(60, 3.5e-3));  // each stall passes 3 deadlines: 0.29 %
  FailSafeInput in = input(9);
  const FailSafeVerdict v = judge_failsafe(stats, stock_vm(), in);
  EXPECT_NEAR(v.predicted_overrun_fraction, 180.0 / 61440, 1e-9);
  EXPECT_FALSE(v.overruns_hold);
  EXPECT_THAT(v.refusal(), HasSubstr("max_overrun_fraction: 0.0059"));
  in.overrun_tolerance = 0.005;
  EXPECT_FALSE(judge_failsafe(stats, stock_vm(), in).refused());
  in.overrun_tolerance = -1;  // not checked
  EXPECT_TRUE(judge_failsafe(stats, stock_vm(), in).overruns_hold);
}

TEST(Verdict, AMachineOverrunningMostStepsIsNotOfferedATolerance) {
  WakeupSamples s = minute(0, 0);
  for (std::size_t i = 0; i < s.lateness[0].size(); i += 4) s.lateness[0][i] = 1.5e-3;  // 25 %
  const FailSafeVerdict v = judge_failsafe(LatencyStats(s), stock_vm(), input(3));
  EXPECT_FALSE(v.overruns_hold);
  EXPECT_THAT(v.refusal(), Not(HasSubstr("max_overrun_fraction:")));
  EXPECT_THAT(v.refusal(), HasSubstr("25.0 % of the steps would overrun"));
}

TEST(Verdict, ACleanMachineHoldsTheDefaultWindow) {
  const FailSafeVerdict v = judge_failsafe(LatencyStats(minute(0, 0)), stock_vm(), input(3));
  EXPECT_TRUE(v.window_holds);
  EXPECT_TRUE(v.overruns_hold);
  EXPECT_FALSE(v.refused());
  EXPECT_LE(v.required_steps, 2);
  EXPECT_TRUE(v.fixes.empty());
}

TEST(Verdict, LinkJitterWidensTheWindow) {
  const LatencyStats stats(minute(60, 3.5e-3));
  FailSafeInput in = input(3);
  const double without = judge_failsafe(stats, stock_vm(), in).required_window_ms;
  in.max_link_jitter = 0.5e-3;
  EXPECT_NEAR(judge_failsafe(stats, stock_vm(), in).required_window_ms - without,
              4 * std::sqrt(2.0) * 0.5, 1e3 * kDt);  // whole steps
}

TEST(Verdict, ManyStallsFitAnExponentialTail) {
  // Stalls of 0.6 .. 3 ms, geometrically fewer as they get longer: the rate beyond the measured
  // ones comes from the fitted tail, so a longer run needs a longer window.
  WakeupSamples s = minute(0, 0);
  std::size_t i = 0;
  for (int n = 400, k = 0; n >= 1; n /= 2, ++k)
    for (int j = 0; j < n; ++j) s.lateness[0][i++ * 7] = 0.6e-3 + 0.3e-3 * k;
  const LatencyStats stats(s);
  EXPECT_GT(stall_rate_per_minute(stats, 5e-3), 0.0);
  EXPECT_LT(stall_rate_per_minute(stats, 5e-3), stall_rate_per_minute(stats, 4e-3));
  const double short_run = judge_failsafe(stats, stock_vm(), input(3, 10)).required_window_ms;
  const double long_run = judge_failsafe(stats, stock_vm(), input(3, 3600)).required_window_ms;
  EXPECT_GT(long_run, short_run);
}

TEST(FailSafeInput, FromADeployment) {
  config::Deployment d;
  ASSERT_TRUE(google::protobuf::TextFormat::ParseFromString(
      "clock: REAL_TIME answer_window_ms: 10 command_watchdog_ms: 8 max_overrun_fraction: 0.002 "
      "pin_loop: true loop_cpu: 1 "
      "nodes { id: 1 kind: SUBSTRUCTURE } "
      "nodes { id: 2 kind: ACTUATOR_EMULATOR receive_lag { one_way_delay: 0.007 jitter: 0.0005 } }",
      &d));
  const FailSafeInput in = failsafe_input(d, kDt, 15, {0});
  EXPECT_EQ(in.answer_steps, 11);   // ceil(10.24)
  EXPECT_EQ(in.watchdog_steps, 9);  // ceil(8.19)
  EXPECT_DOUBLE_EQ(in.max_link_jitter, 0.0005);
  EXPECT_DOUBLE_EQ(in.overrun_tolerance, 0.002);
  EXPECT_DOUBLE_EQ(in.step_work, 0.5 * kDt);  // node 1 is waited for
  EXPECT_EQ(in.loop_cpu, 1);
  EXPECT_EQ(in.cpus, (std::vector<int>{0, 1}));
  d.mutable_nodes(0)->mutable_send_lag()->set_one_way_delay(0.001);  // nobody waited for
  EXPECT_DOUBLE_EQ(failsafe_input(d, kDt, 15, {0}).step_work, 0.05 * kDt);
}

}  // namespace
}  // namespace rths::rt_check
