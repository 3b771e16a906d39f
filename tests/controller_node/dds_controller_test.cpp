// A run through a controller node: the coordinator and the controller node are processes over
// Cyclone DDS on loopback (rths launch's sequence), the controller node talks UDP on 127.0.0.1 to
// the controller emulator, another process. The shared DDS domain, each test on topics of its
// own; UDP ports 47150-47159.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <thread>

#include "../runtime/test_support.h"
#include "controller_node/udp_link.h"
#include "link_text.h"
#include "tests/support/dds_scope.h"
#include "tests/support/real_time_run.h"

namespace rths {
namespace {

class DdsController : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

std::string study(int node_port, int peer_port, double duration, const std::string& extra = "") {
  return test::paper_frame_study(duration,
                                 "deployment { nodes { id: 2 kind: CONTROLLER controller { " +
                                     test::controller_link_text(node_port, peer_port, extra) +
                                     " } } limits { max_displacement: 0.5 } }");
}

// The controller emulator for `text`, started before the run and waited for until it listens (a
// frame sent before it binds would be lost, and a lockstep run holds on a lost frame).
util::ChildProcess start_emulator(const std::string& name, const std::string& text,
                                  const std::string& case_name,
                                  const std::vector<std::string>& extra = {}) {
  const auto dir = test::scratch_dir(name + "_controller");
  std::vector<std::string> args = {"--config",       test::write_config(dir, text).string(),
                                   "--node-id",      "2",
                                   "--case",         case_name,
                                   "--idle-timeout", "60"};
  args.insert(args.end(), extra.begin(), extra.end());
  util::ChildProcess emulator(test::program("rths-controller-emulator", "controller_emulator"),
                              args, dir / "controller_emulator.log");
  for (int i = 0; i < 400; ++i) {
    if (test::read_file(emulator.log_file()).find("listening on") != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  return emulator;
}

TEST_F(DdsController, LockstepThroughTheControllerEqualsInProcessBitForBitDespiteARogue) {
  const std::string text = study(47150, 47151, 2.0);
  util::ChildProcess emulator = start_emulator("controller_lockstep", text, "lag_shift_14ms");
  // A rogue on this host floods the node's port from another port for the whole run.
  std::atomic<bool> done{false};
  std::thread rogue([&] {
    controller_node::UdpLink udp("127.0.0.1", 47152, "127.0.0.1", 47150);
    const std::vector<std::uint8_t> frame(24, 0);
    while (!done) {
      udp.send(frame.data(), frame.size());
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  const auto run =
      test::launch("controller_lockstep", text, "lag_shift_14ms", test::scope_dds_to_this_test());
  done = true;
  rogue.join();
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  test::expect_record_equals(run.record, test::reference_result(text, "lag_shift_14ms"));
  // Every answered step records the frame's round trip to the controller and its status.
  const auto steps = run.record.steps();
  for (std::size_t k = 1; k < steps.size(); ++k) {
    ASSERT_EQ(steps[k]->links_size(), 1) << "step " << k;
    ASSERT_GT(steps[k]->links(0).controller_round_trip(), 0.0) << "step " << k;
    ASSERT_LT(steps[k]->links(0).controller_round_trip(), 1.0) << "step " << k;
    ASSERT_EQ(steps[k]->links(0).controller_status(), 0) << "step " << k;
  }
  for (int code : run.launch.node_exits) EXPECT_EQ(code, 0);
  EXPECT_EQ(emulator.wait_for(std::chrono::seconds(10)), 0) << emulator.log_tail();
  // The node's socket is connected to the controller: the kernel dropped the rogue's frames
  // before they took room in its buffer, so the link report is clean.
  const std::string node_log = test::read_file(run.dir / "node_2.log");
  const std::string accepted = std::to_string(run.record.steps().size() - 1) + " accepted";
  EXPECT_NE(node_log.find(accepted + ", 0 answered late, 0 lost (no answer within the reply "
                                     "timeout); UDP frames rejected: none"),
            std::string::npos)
      << node_log;
  ASSERT_NE(run.record.footer(), nullptr);
  ASSERT_EQ(run.record.footer()->node_rejects_size(), 1);
  const runtime::ControllerReport& link = run.record.footer()->node_rejects(0).controller();
  EXPECT_EQ(link.frames_accepted(), run.record.steps().size() - 1);
  EXPECT_EQ(link.wrong_source(), 0u);
  EXPECT_GE(link.held_after(), 0.0) << "the emulator reports held before the STOP frame";
  EXPECT_NE(emulator.log_tail(4000).find("status STOP received"), std::string::npos);
}

TEST_F(DdsController, ASilentControllerHoldsTheRunWithinItsReplyTimeoutAndTheRigIsToldToHold) {
  const std::string text = study(47153, 47154, 2.0, "reply_timeout_ms: 200");
  util::ChildProcess emulator =
      start_emulator("controller_silent", text, "reference", {"--answer-frames", "300"});
  const auto run =
      test::launch("controller_silent", text, "reference", test::scope_dds_to_this_test());
  const std::string coordinator_log = test::read_file(run.launch.coordinator_log);
  EXPECT_EQ(run.launch.coordinator_exit, 1) << coordinator_log;
  // The node's HOLD names the controller's silence: it came within the node's 200 ms, before the
  // coordinator's own step timeout (2 s) could judge the step.
  EXPECT_NE(coordinator_log.find("did not answer frame 301 (step 301) within 200 ms"),
            std::string::npos)
      << coordinator_log;
  ASSERT_NE(run.record.footer(), nullptr);
  EXPECT_FALSE(run.record.footer()->ok());
  EXPECT_LE(run.record.steps().size(), 302u);  // nothing recorded past the silence
  emulator.terminate();
  const std::string emulator_log = test::read_file(emulator.log_file());
  EXPECT_NE(emulator_log.find("status HOLD received (frame 302)"), std::string::npos)
      << emulator_log;
}

TEST_F(DdsController, AKilledControllerHoldsTheRunWithinItsReplyTimeout) {
  const std::string text = study(47155, 47156, 30.0, "reply_timeout_ms: 200");
  util::ChildProcess emulator = start_emulator("controller_killed", text, "reference");
  // Killed once the run is under way: its live record holds a few hundred intact steps.
  const auto record = std::filesystem::temp_directory_path() /
                      ("rths_runtime_controller_killed_" + std::to_string(getpid())) /
                      "run.rthsrec";
  std::thread killer([&] {
    test::wait_for_steps(record, 301, std::chrono::seconds(30));
    emulator.signal(SIGKILL);
  });
  const auto run =
      test::launch("controller_killed", text, "reference", test::scope_dds_to_this_test());
  killer.join();
  const std::string coordinator_log = test::read_file(run.launch.coordinator_log);
  EXPECT_EQ(run.launch.coordinator_exit, 1) << coordinator_log;
  EXPECT_NE(coordinator_log.find("within 200 ms (1 lost in a row)"), std::string::npos)
      << coordinator_log;
  const std::string node_log = test::read_file(run.dir / "node_2.log");
  EXPECT_NE(node_log.find("HOLD frames (status 1) to the controller"), std::string::npos)
      << node_log;
  bool named = false;
  for (const auto& e : run.record.entries)
    named = named || (e.has_event() &&
                      e.event().what().rfind("HOLD sent to the controller nodes: ", 0) == 0);
  EXPECT_TRUE(named) << "the coordinator's HOLD event names whom it went to";
  EXPECT_GT(run.record.steps().size(), 300u);    // killed mid-run, not at the start
  EXPECT_LT(run.record.steps().size(), 30000u);  // stopped before the motion's end
}

// A controller slower than the host (one answer per 2 ms at dt = 1 ms, in order) falls further
// behind every frame (the paper frame steps at dt = 1 ms). Before, the node waited for each answer
// on the DDS thread and the coordinator applied answers seconds old. Now every applied answer is
// within the answer window, and the run HOLDs within the window + 2 ms of the first answer that
// would be older, naming it.
TEST_F(DdsController, AControllerThatFallsBehindHoldsWithinTheAnswerWindow) {
  constexpr double kWindowMs = 20.0;
  const std::string text = test::paper_frame_study(
      4.0,
      "deployment { clock: REAL_TIME liveliness_timeout: 2 heartbeat_period: 0.02 "
      "answer_window_ms: 20 command_watchdog_ms: 20 max_overrun_fraction: -1 "
      "min_answer_fraction: -1 nodes { id: 2 kind: CONTROLLER controller { " +
          test::controller_link_text(47157, 47158, "reply_timeout_ms: 8") +
          " } } limits { max_displacement: 0.5 } }");
  util::ChildProcess emulator =
      start_emulator("controller_behind", text, "reference", {"--answer-period-ms", "2"});
  const auto witnessed = test::launch_witnessed("controller_behind", text, "reference",
                                                test::scope_dds_to_this_test());
  const auto& run = witnessed.run;
  const std::string coordinator_log = test::read_file(run.launch.coordinator_log);
  EXPECT_EQ(run.launch.coordinator_exit, 1) << coordinator_log;
  ASSERT_NE(run.record.footer(), nullptr);
  EXPECT_FALSE(run.record.footer()->ok());
  // Named: the node's own staleness limit, calling the controller late (its answers come, after
  // their timeout), or the coordinator's window on the answer's age; a stall of this machine may
  // pass another window first.
  const std::string& status = run.record.footer()->status();
  const bool named = status.find("answers late: frame") != std::string::npos ||
                     status.find("never applied") != std::string::npos;
  if (const auto burned = test::loop_cpu_over_bound(coordinator_log)) FAIL() << *burned;
  if (!named)
    if (const auto why = test::machine_stalled(status, *run.record.header(), witnessed.machine))
      GTEST_SKIP() << *why;
  EXPECT_TRUE(named) << status;
  // No applied answer older than the window, step by step on the record.
  const double dt = 0.001;  // the paper frame study's
  const auto window_steps = static_cast<std::int64_t>(std::ceil(kWindowMs * 1e-3 / dt));
  std::int64_t oldest = 0;
  const auto steps = run.record.steps();
  for (const auto* step : steps)
    for (const auto& link : step->links())
      if (link.answered_step() > 0) oldest = std::max(oldest, step->step() - link.answered_step());
  EXPECT_LE(oldest, window_steps);
  // Stopped early: the motion is 4 s (4000 steps); the backlog passes the window within 0.1 s.
  EXPECT_LT(steps.size(), 400u);
  emulator.terminate();
}

}  // namespace
}  // namespace rths
