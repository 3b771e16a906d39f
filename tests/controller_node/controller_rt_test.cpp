// The controller link in real time across two network namespaces: a short version of
// bench/controller_rt (tests/support/controller_trial.h). A 1024 Hz coordinator and its
// CONTROLLER node in one namespace, the controller emulator with its plant paced at 4096 Hz in
// another. Verdicts only, never the bench's timing targets (a busy 2-core machine must pass): the
// record's controller round trip is at least the lag the emulator injects and near it; a killed
// emulator stops the run with a HOLD and the node sends its HOLD frame; a silenced one receives
// that frame once it runs again. Skipped (with the reason) where namespaces cannot be made.
// The shared DDS domain, each test on topics of its own (`ip netns exec` keeps the environment);
// UDP ports 47170-47175.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>

#include "../runtime/test_support.h"
#include "deploy/netns.h"
#include "tests/support/controller_trial.h"
#include "tests/support/dds_scope.h"

namespace rths::test {
namespace {

constexpr double kLagMs = 0.3;

class ControllerRt : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto reason = deploy::namespace_support()) GTEST_SKIP() << *reason;
  }
  static ControllerTrialSpec spec(ControllerFault fault, int index) {
    ControllerTrialSpec s;
    s.fault = fault;
    s.seconds = 1.5;
    s.answer_lag_ms = kLagMs;
    s.answer_window_ms = 100;  // a busy machine's stalls must not stop a run before its fault
    s.domain = test::scope_dds_to_this_test();
    s.node_port = 47170 + 2 * index;
    s.peer_port = s.node_port + 1;
    s.subnet = "10.231.41";
    // The verdicts are about the link; a busy machine's late steps are not.
    s.deployment_extra = "max_overrun_fraction: -1 min_answer_fraction: -1";
    s.fault_step = 300;
    s.dir = std::filesystem::temp_directory_path() /
            ("rths_controller_rt_test_" + std::to_string(index));
    s.binary_dir = RTHS_BINARY_DIR;
    s.motion_path = motion_path();
    return s;
  }
  // A run the fail-safe stopped before its fault (or a healthy run stopped at all) says the
  // machine stalled for the whole window, not what the test is about: up to 3 runs.
  static ControllerTrialResult run(const ControllerTrialSpec& s) {
    ControllerTrialResult r;
    for (int attempt = 1; attempt <= 3; ++attempt) {
      r = run_controller_trial(s);
      const bool stalled =
          s.fault == ControllerFault::kNone ? r.coordinator_exit != 0 : !r.fault_delivered;
      if (!stalled) break;
      std::printf("attempt %d: the run stopped before the test could judge it: %s\n", attempt,
                  r.status.c_str());
    }
    return r;
  }
};

TEST_F(ControllerRt, TheRecordsControllerRoundTripFollowsTheLagTheEmulatorInjects) {
  const ControllerTrialResult r = run(spec(ControllerFault::kNone, 0));
  EXPECT_EQ(r.coordinator_exit, 0) << r.status;
  EXPECT_EQ(r.emulator_exit, 0) << "the emulator leaves on the node's STOP frame";
  ASSERT_GT(r.controller_round_trip.count, 100u) << r.status;
  EXPECT_GE(r.controller_round_trip.median, kLagMs * 1e-3);
  EXPECT_LT(r.controller_round_trip.median, kLagMs * 1e-3 + 2e-3);
  EXPECT_GE(r.round_trip.median, r.controller_round_trip.median)
      << "the DDS round trip holds the frame's";
  EXPECT_GT(r.plant_periods, static_cast<std::uint64_t>(1.5 * 4096 / 2));
  EXPECT_FALSE(r.hold_frame_sent);
}

TEST_F(ControllerRt, AKilledEmulatorStopsTheRunWithAHoldAndTheNodeSendsItsHoldFrame) {
  const ControllerTrialResult r = run(spec(ControllerFault::kKill, 1));
  ASSERT_TRUE(r.fault_delivered) << r.why_not;
  EXPECT_EQ(r.coordinator_exit, 1) << r.status;
  EXPECT_GE(r.hold_ms, 0.0) << "no HOLD after the kill; status: " << r.status;
  EXPECT_TRUE(r.hold_frame_sent);
  EXPECT_LT(r.record_steps, static_cast<long>(1.5 * 1024)) << "the run stopped early";
  EXPECT_EQ(r.emulator_exit, 128 + SIGKILL);
}

TEST_F(ControllerRt, ASilencedEmulatorReceivesTheHoldFrameOnceItRunsAgain) {
  for (int trial = 2; trial <= 3; ++trial) {
    const ControllerTrialResult r = run(spec(ControllerFault::kStop, trial));
    ASSERT_TRUE(r.fault_delivered) << r.why_not;
    EXPECT_EQ(r.coordinator_exit, 1) << r.status;
    EXPECT_GE(r.hold_ms, 0.0) << "no HOLD after SIGSTOP; status: " << r.status;
    EXPECT_TRUE(r.hold_frame_sent);
    EXPECT_TRUE(r.hold_frame_received) << "trial " << trial;
    EXPECT_EQ(r.emulator_exit, 0) << "after SIGCONT it reads the HOLD and STOP frames and leaves";
  }
}

}  // namespace
}  // namespace rths::test
