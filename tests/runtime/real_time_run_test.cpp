// The rule by which the suite puts a real-time run's failure down to this machine
// (tests/support/real_time_run.h): only a window a stall can pass, only beside a stall of at
// least half of it or a CPU share under the loaded mark; and the loop CPU bound that never skips.
#include "tests/support/real_time_run.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace rths {
namespace {

runtime::RunHeader header(double dt, const std::string& controller_block = "") {
  runtime::RunHeader h;
  h.set_dt(dt);
  config::Deployment* d = h.mutable_study()->mutable_deployment();
  d->set_clock(config::Deployment::REAL_TIME);
  d->set_answer_window_ms(20);
  if (!controller_block.empty()) {
    config::NodeSpec* node = d->add_nodes();
    node->set_id(2);
    node->set_kind(config::NodeSpec::CONTROLLER);
    node->mutable_controller()->set_reply_timeout_ms(8);
  }
  return h;
}

test::MeasuredPlatform stalled_for(double seconds) {
  test::MeasuredPlatform m;
  m.max = seconds;
  m.text = "max " + std::to_string(seconds * 1e3) + " ms";
  return m;
}

TEST(StallRule, EachWindowAStallCanPassIsReadFromItsStatus) {
  const runtime::RunHeader h = header(1.0 / 1024, "controller");
  EXPECT_NEAR(*test::stall_window(
                  "node 2: no answer for 21 consecutive steps (steps 1727 to 1747; its newest "
                  "answers step 1726)",
                  h),
              21.0 / 1024, 1e-12);
  EXPECT_NEAR(*test::stall_window("node 2: its newest answer is to step 9 at step 40: 31 steps "
                                  "(30.273438 ms) old, beyond its answer window of 20 steps "
                                  "(19.531250 ms); an answer that old is never applied",
                                  h),
              0.01953125, 1e-12);
  EXPECT_NEAR(*test::stall_window("node 2 held the rig: command watchdog: no fresh command for "
                                  "21.000000 ms (limit 20.500000 ms)",
                                  h),
              0.0205, 1e-12);
  EXPECT_NEAR(*test::stall_window("held on its own at its step 50: step 50: controller: the "
                                  "controller 127.0.0.1:47307 did not answer frame 42 (step 42) "
                                  "within 8.000000 ms (10 lost in a row)",
                                  h),
              0.008, 1e-12);
  EXPECT_NEAR(*test::stall_window("node 2's controller link was not clean: 9 frames lost, 15 "
                                  "answered late, 0 rejected",
                                  h),
              0.008, 1e-12);
}

TEST(StallRule, FailuresNoStallCausesAreNeverTheMachines) {
  const runtime::RunHeader h = header(0.001, "controller");
  for (const char* status :
       {"node 2's controller link was not clean: 0 frames lost, 0 answered late, 3 rejected",
        "node 2: the run's state left its limits: |u| 0.3 m > 0.2 m", "diverged at step 40",
        "start-up timed out after 10 s: node 2"}) {
    EXPECT_FALSE(test::stall_window(status, h).has_value()) << status;
    EXPECT_FALSE(test::machine_stalled(status, h, stalled_for(10.0)).has_value()) << status;
  }
  // Without a controller node there is no reply timeout to have passed.
  EXPECT_FALSE(test::stall_window("node 2's controller link was not clean: 1 frames lost, 0 "
                                  "answered late, 0 rejected",
                                  header(0.001))
                   .has_value());
}

TEST(StallRule, AWindowsFailureIsTheMachinesOnlyBesideAStallOfHalfIt) {
  const runtime::RunHeader h = header(0.001);
  const std::string status = "node 2: no answer for 30 consecutive steps (steps 1 to 30)";
  EXPECT_FALSE(test::machine_stalled(status, h, stalled_for(0.0149)).has_value());
  const auto why = test::machine_stalled(status, h, stalled_for(0.015));
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("max 15.0"), std::string::npos) << *why;
  EXPECT_NE(why->find("30.0 ms window"), std::string::npos) << *why;
  EXPECT_NE(why->find(status), std::string::npos) << *why;
}

// Beside a machine that cannot pace the loop (p99 >= dt / 2) a window's failure is the machine's
// with no single stall of half the window; beside one that can, it is the code's.
TEST(StallRule, AWindowsFailureBesideAMachineThatCannotPaceIsTheMachines) {
  const runtime::RunHeader h = header(1.0 / 1024);
  const std::string status =
      "its newest answer is to step 108 at step 130: 22 steps (21.484375 ms) old, beyond its "
      "answer window of 21 steps (20.507812 ms); an answer that old is never applied";
  test::MeasuredPlatform machine = stalled_for(0.0048);
  machine.p99 = 0.00048;
  EXPECT_FALSE(test::machine_stalled(status, h, machine).has_value());
  machine.p99 = 0.0037;
  const auto why = test::machine_stalled(status, h, machine);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("p99 wake-up lateness 3.70 ms is at least half the 0.98 ms step"),
            std::string::npos)
      << *why;
  EXPECT_NE(why->find("past the 20.5 ms window"), std::string::npos) << *why;
  EXPECT_FALSE(test::machine_stalled("diverged at step 40", h, machine).has_value());
}

// A failed real-time verdict is the machine's only where its p99 wake-up lateness reached half a
// step; beside a machine that paces the loop it is the code's, however long one stall was.
TEST(StallRule, MissedDeadlinesAreTheMachinesOnlyWhereItCouldNotPaceTheLoop) {
  const runtime::RunHeader h = header(0.001);
  const std::string status =
      "completed with deadline misses: 818 overruns in 999 steps (81.9 %, more than half; worst "
      "streak 496)";
  test::MeasuredPlatform machine = stalled_for(0.050);
  machine.p99 = 0.00049;
  EXPECT_FALSE(test::machine_stalled(status, h, machine).has_value());
  machine.p99 = 0.0005;
  const auto why = test::machine_stalled(status, h, machine);
  ASSERT_TRUE(why.has_value());
  EXPECT_NE(why->find("p99 wake-up lateness 0.50 ms is at least half the 1.00 ms step"),
            std::string::npos)
      << *why;
  EXPECT_NE(why->find(status), std::string::npos) << *why;
  // Another failure beside the same machine is not excused by its pacing.
  EXPECT_FALSE(test::machine_cannot_pace("diverged at step 40", h, machine).has_value());
}

// A timing failure (the deadline verdict or a window) beside a machine whose CPU share was under
// kLoadedCpuShare is the machine's, naming the share; any other failure is not, nor one beside a
// machine that gave its busy threads their CPUs.
TEST(StallRule, ATimingFailureBesideALoadedMachineIsTheMachines) {
  const runtime::RunHeader h = header(0.001);
  const std::string missed = "completed with deadline misses: 211 overruns in 999 steps";
  const std::string window = "node 2: no answer for 30 consecutive steps (steps 1 to 30)";
  const std::string few = "failed: node 2 answered 585 of 592 steps (at least 99 % needed)";
  test::MeasuredPlatform machine = stalled_for(0.001);
  machine.p99 = 0.0001;
  machine.cpu_share = test::kLoadedCpuShare;
  for (const std::string& status : {missed, window, few})
    EXPECT_FALSE(test::machine_stalled(status, h, machine).has_value()) << status;
  machine.cpu_share = 0.51;
  for (const std::string& status : {missed, window, few}) {
    const auto why = test::machine_stalled(status, h, machine);
    ASSERT_TRUE(why.has_value()) << status;
    EXPECT_NE(why->find("a busy thread got 0.51 of its CPU, under the 0.70"), std::string::npos)
        << *why;
    EXPECT_NE(why->find(status), std::string::npos) << *why;
  }
  EXPECT_FALSE(test::machine_loaded("diverged at step 40", h, machine).has_value());
  EXPECT_FALSE(test::machine_loaded("failed: node 2 sent a garbage message", h, machine));
}

// The loop's CPU time per step bounds the code whatever the machine: over the bound, or a
// completed run's summary without the figure, is a failure; a run that never printed a summary
// is judged by its status instead.
TEST(LoopCpuBound, AMedianOverTheBoundOrAMissingFigureFails) {
  const auto line = [](double median_ms) {
    return "status: completed\nloop CPU per step: median " + std::to_string(median_ms) +
           " ms, p99 0.4 ms, max 0.9 ms over 999 steps\n";
  };
  EXPECT_NEAR(test::loop_cpu_median(line(0.087)).value_or(0.0), 0.087e-3, 1e-12);
  EXPECT_FALSE(test::loop_cpu_over_bound(line(test::kLoopCpuMedianBound * 1e3)).has_value());
  const auto over = test::loop_cpu_over_bound(line(0.55));
  ASSERT_TRUE(over.has_value());
  EXPECT_NE(over->find("median 0.550 ms of CPU per step, over the 0.200 ms bound"),
            std::string::npos)
      << *over;
  EXPECT_TRUE(test::loop_cpu_over_bound("status: completed\nsteps: 1000\n").has_value());
  EXPECT_FALSE(test::loop_cpu_over_bound("start-up timed out after 10 s").has_value());
}

// The CPU share is each busy thread's CPU time over its wall time: one extra busy thread per CPU
// beside the measurement halves it, which is under the loaded mark however quiet the machine.
TEST(CpuShare, BusyThreadsBesideTheMeasurementMarkTheMachineLoaded) {
  const double alone = test::measure_cpu_share(0.1);
  EXPECT_GT(alone, 0.0);
  EXPECT_LE(alone, 1.01);
  std::atomic<bool> stop{false};
  std::vector<std::thread> burners;
  for (unsigned i = 0; i < std::max(1u, std::thread::hardware_concurrency()); ++i)
    burners.emplace_back([&stop] {
      while (!stop.load(std::memory_order_relaxed)) {}
    });
  const double beside = test::measure_cpu_share(0.3);
  stop = true;
  for (std::thread& burner : burners) burner.join();
  EXPECT_LT(beside, test::kLoadedCpuShare);
}

}  // namespace
}  // namespace rths
