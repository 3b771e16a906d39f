// Distributed runs over Cyclone DDS on loopback: real processes (coordinator, substructure node,
// actuator emulator), all on the shared DDS domain, each test on topics of its own
// (tests/support/dds_scope.h).
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>

#include "runtime/node/lag.h"
#include "test_support.h"
#include "tests/support/dds_scope.h"
#include "tests/support/real_time_run.h"
#include "transport/topic_scope.h"
#include "util/process.h"

namespace rths {
namespace {

using namespace std::chrono_literals;

class DdsRun : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_F(DdsRun, LockstepEqualsTheInProcessRunBitForBit) {
  const std::string text = test::paper_frame_study(3, "");
  const auto run =
      test::launch("lockstep_equal", text, "lag_shift_14ms", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_FALSE(run.record.truncated);
  ASSERT_NE(run.record.footer(), nullptr);
  EXPECT_TRUE(run.record.footer()->ok());
  test::expect_record_equals(run.record, test::reference_result(text, "lag_shift_14ms"));
  for (int code : run.launch.node_exits) EXPECT_EQ(code, 0);
}

// Multi-rate: the emulator's servo loop at 4x the integrator's rate, in simulated time.
TEST_F(DdsRun, MultiRateLockstepEqualsTheInProcessMultiRateRunBitForBit) {
  const std::string text = test::paper_frame_study(2, "servo { rate: 4000 }");
  const auto run =
      test::launch("multi_rate", text, "lag_shift_14ms", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  const core::SimulationResult multi_rate = test::reference_result(text, "lag_shift_14ms");
  test::expect_record_equals(run.record, multi_rate);
  // The servo loop is not a no-op: the ramp changes what the specimen sees.
  const core::SimulationResult single_rate =
      test::reference_result(test::paper_frame_study(2, ""), "lag_shift_14ms");
  EXPECT_GT((multi_rate.realised - single_rate.realised).cwiseAbs().maxCoeff(), 1e-9);
}

// Real time with the servo at 4x: it streams feedback every servo period; the coordinator takes the
// newest sample and counts the servo's periods and overruns from the heartbeats.
TEST_F(DdsRun, RealTimeServoLoopStreamsFeedbackAtItsOwnRate) {
  const std::string text = test::paper_frame_study(
      1.0,
      "servo { rate: 4000 } deployment { clock: REAL_TIME max_overrun_fraction: -1 "
      "max_missed_answers: 30 command_watchdog_periods: 30 min_answer_fraction: -1 }");
  // The streaming's mechanics are judged here, not whether this machine keeps a 4 kHz servo.
  const auto witnessed =
      test::launch_witnessed("servo_real_time", text, "reference", test::scope_dds_to_this_test());
  RTHS_ASSERT_REAL_TIME_RUN_COMPLETED(witnessed);
  const auto& run = witnessed.run;
  const auto* footer = run.record.footer();
  ASSERT_NE(footer, nullptr);
  const double steps = static_cast<double>(footer->counters().steps());
  // Ticks as of the emulator's last heartbeat (every 50 ms): about 4 per step, on a machine that
  // wakes the servo within its period (p99). A busier one runs late ticks back to back, behind
  // the grid (runtime/rt/pacing.h), and its count trails: then at least a quarter of them.
  const double kept = witnessed.machine.p99 < 0.25e-3 ? 0.7 : 0.25;
  EXPECT_GT(static_cast<double>(footer->counters().servo_ticks()), kept * 4 * steps)
      << witnessed.machine.text;
  EXPECT_LT(static_cast<double>(footer->counters().servo_ticks()), 1.2 * 4 * steps);
  // Later servo samples of an answered step replace the measurement without being "duplicates".
  EXPECT_EQ(footer->counters().duplicate(), 0u);
  EXPECT_NE(test::read_file(run.launch.coordinator_log).find("servo loops:"), std::string::npos);
}

// realtime_priority: every process of the run says, in its log, that its loop and its DDS
// receive threads went on SCHED_FIFO (runtime/rt/fifo_test checks that such a line is true of
// the threads), and the coordinator's record carries the line as an event. Where this process
// may not use SCHED_FIFO, every log names the refusal instead and the run still completes.
TEST_F(DdsRun, RealTimePriorityRaisesEveryProcesssLoopAndReceiveThreads) {
  const std::string text = test::paper_frame_study(
      0.5,
      "deployment { clock: REAL_TIME realtime_priority: 20 max_overrun_fraction: -1 "
      "max_missed_answers: 30 command_watchdog_periods: 30 }");
  const auto witnessed =
      test::launch_witnessed("fifo", text, "reference", test::scope_dds_to_this_test());
  RTHS_ASSERT_REAL_TIME_RUN_COMPLETED(witnessed);
  const auto& run = witnessed.run;
  std::vector<std::string> logs;
  for (const auto& entry : std::filesystem::directory_iterator(run.dir))
    if (entry.path().extension() == ".log") logs.push_back(test::read_file(entry.path()));
  ASSERT_EQ(logs.size(), 3u) << "one log per process: the coordinator and two nodes";
  const bool refused = logs[0].find("SCHED_FIFO 20 refused (") != std::string::npos;
  for (const std::string& log : logs) {
    if (refused) {
      EXPECT_NE(log.find("SCHED_FIFO 20 refused ("), std::string::npos) << log;
      continue;
    }
    const auto at = log.find("SCHED_FIFO 20: loop, ");
    ASSERT_NE(at, std::string::npos) << log;
    const std::string line = log.substr(at, log.find('\n', at) - at);
    EXPECT_NE(line.find("recv"), std::string::npos) << line;
    EXPECT_NE(line.find("dq.user"), std::string::npos) << line;
  }
  bool recorded = false;
  for (const runtime::RecordEntry& entry : run.record.entries)
    recorded = recorded || (entry.has_event() &&
                            entry.event().what().find("SCHED_FIFO 20") != std::string::npos);
  EXPECT_TRUE(recorded);
  if (refused) GTEST_SKIP() << "this machine refuses SCHED_FIFO 20: " << logs[0].substr(0, 400);
}

TEST_F(DdsRun, SplitStoreysAcrossTwoSubstructureNodesEqualInProcess) {
  const std::string text = test::two_storey_study(
      2, "cases { name: \"lag\" delay { first_order { time_constant: 0.005 } } }",
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE storeys: [1] } "
      "nodes { id: 3 kind: SUBSTRUCTURE storeys: [2] } nodes { id: 2 kind: ACTUATOR_EMULATOR } }",
      "substructuring { experimental_fraction: 0.5 model { bilinear { yield_displacement: 0.004 "
      "post_yield_ratio: 0.1 } } }");
  const auto run = test::launch("split", text, "lag", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  test::expect_record_equals(run.record, test::reference_result(text, "lag"));
  EXPECT_EQ(run.launch.node_exits.size(), 3u);
}

TEST_F(DdsRun, InjectedWallClockLagIsMeasuredAndLeavesTheLockstepResultUnchanged) {
  constexpr double kOneWay = 0.001;
  const std::string text = test::paper_frame_study(
      0.4,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR "
      "receive_lag { one_way_delay: 0.001 } send_lag { one_way_delay: 0.001 jitter: 0.0002 seed: "
      "3 } } }");
  const auto run =
      test::launch("injected_lag", text, "lag_shift_14ms", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  test::expect_record_equals(run.record, test::reference_result(text, "lag_shift_14ms"));
  std::vector<double> injected, round_trip, fast_round_trip;
  for (const runtime::StepRecord* s : run.record.steps()) {
    for (const runtime::LinkSample& link : s->links()) {
      EXPECT_EQ(link.answered_step(), s->step());
      if (link.node_id() == 2) {
        injected.push_back(link.injected_lag());
        round_trip.push_back(link.round_trip());
        // The round trip contains the injected lag plus the real one.
        EXPECT_GE(link.round_trip(), link.injected_lag());
      } else {
        fast_round_trip.push_back(link.round_trip());
      }
    }
  }
  ASSERT_EQ(injected.size(), run.record.steps().size() - 1);
  const auto inj = runtime::summarize(injected);
  EXPECT_NEAR(inj.mean, 2 * kOneWay, 0.0002);
  EXPECT_GT(runtime::summarize(round_trip).median, 2 * kOneWay);
  EXPECT_LT(runtime::summarize(fast_round_trip).median, 2 * kOneWay);
}

TEST_F(DdsRun, DelayStageAtTheEmulatorsInputReproducesTheInProcessDelayedResult) {
  const std::string text = test::paper_frame_study(
      2,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR "
      "receive_delay { jitter { mean_delay: 0.01 std_dev: 0.003 seed: 5 } } } }");
  const auto run = test::launch("node_delay", text, "reference", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  test::expect_record_equals(run.record, test::reference_result(text, "jitter"));
}

// `rths launch` of one case of the study at `config` on the shared domain, its topics scoped by
// `scope` (transport/topic_scope.h), started now; it writes its record to `record`.
struct ScopedLaunch {
  util::ChildProcess process;
  std::filesystem::path record;
};

ScopedLaunch launch_scoped(const std::filesystem::path& config, const std::string& case_name,
                           const std::string& scope) {
  const std::filesystem::path dir = config.parent_path();
  const std::filesystem::path out = dir / ("out_" + case_name);
  util::ChildOptions options;
  options.environment[transport::kTopicScopeVariable] = scope;
  util::ChildProcess process(std::filesystem::path(RTHS_BINARY_DIR) / "cli" / "rths",
                             {"launch", config.string(), "--case", case_name, "--domain",
                              std::to_string(test::kSharedDomain), "--no-plots", "--bin-dir",
                              RTHS_BINARY_DIR, "--out", out.string()},
                             dir / ("launch_" + case_name + ".log"), options);
  return {std::move(process), out / (case_name + ".rthsrec")};
}

// Messages a run dropped unread (unauthenticated) or rejected as another run's (foreign run),
// by its coordinator and by each node.
std::uint64_t messages_of_another_run(const runtime::RecordContents& record) {
  std::uint64_t count = record.footer()->counters().unauthenticated();
  for (const runtime::NodeRejects& n : record.footer()->node_rejects())
    count += n.rejected().unauthenticated() + n.rejected().foreign_run();
  return count + record.footer()->counters().foreign_run();
}

// Two runs at once on one domain, each on its own topic scope: neither hears a message of the
// other (nothing dropped or rejected), and each equals its own case's in-process run bit for bit.
TEST_F(DdsRun, TwoRunsOnOneDomainWithTheirOwnScopesNeverHearEachOther) {
  const std::string text = test::paper_frame_study(2, "");
  const auto config = test::write_config(test::scratch_dir("own_scopes"), text);
  const std::string scope = test::dds_scope_for("own_scopes", ::getpid());
  ScopedLaunch a = launch_scoped(config, "reference", scope + "_a");
  ScopedLaunch b = launch_scoped(config, "lag_shift_14ms", scope + "_b");
  ASSERT_EQ(a.process.wait_for(120s).value_or(-1), 0) << a.process.log_tail();
  ASSERT_EQ(b.process.wait_for(120s).value_or(-1), 0) << b.process.log_tail();
  const auto record_a = runtime::read_record(a.record);
  const auto record_b = runtime::read_record(b.record);
  test::expect_record_equals(record_a, test::reference_result(text, "reference"));
  test::expect_record_equals(record_b, test::reference_result(text, "lag_shift_14ms"));
  EXPECT_EQ(messages_of_another_run(record_a), 0u);
  EXPECT_EQ(messages_of_another_run(record_b), 0u);
}

// Two runs on one domain and one scope do hear each other: the second starts while the first is
// under way, and each `rths launch` run's own secret (transport/message_mac.h) drops the other's
// messages unread and counts them, so both still complete equal to their in-process runs.
TEST_F(DdsRun, TwoRunsOnOneDomainAndOneScopeDropAndCountEachOthersMessages) {
  const std::string text = test::paper_frame_study(6, "");
  const auto config = test::write_config(test::scratch_dir("one_scope"), text);
  const std::string scope = test::dds_scope_for("one_scope", ::getpid());
  ScopedLaunch a = launch_scoped(config, "reference", scope);
  // Under way once its record holds a step; a launch that ends first fails here, naming why.
  while (!test::wait_for_steps(a.record, 1, 100ms))
    ASSERT_TRUE(a.process.running()) << a.process.log_tail();
  ScopedLaunch b = launch_scoped(config, "lag_shift_14ms", scope);
  ASSERT_EQ(a.process.wait_for(120s).value_or(-1), 0) << a.process.log_tail();
  ASSERT_EQ(b.process.wait_for(120s).value_or(-1), 0) << b.process.log_tail();
  const auto record_a = runtime::read_record(a.record);
  const auto record_b = runtime::read_record(b.record);
  test::expect_record_equals(record_a, test::reference_result(text, "reference"));
  test::expect_record_equals(record_b, test::reference_result(text, "lag_shift_14ms"));
  EXPECT_GT(messages_of_another_run(record_a) + messages_of_another_run(record_b), 0u);
}

TEST_F(DdsRun, RealTimeRunIsPacedAndRecordsLatenessAndAnsweredSteps) {
  // Deadline misses on this shared machine are not what this test judges.
  const std::string text = test::paper_frame_study(
      1.0,
      "deployment { clock: REAL_TIME max_overrun_fraction: -1 max_missed_answers: 30 "
      "command_watchdog_periods: 30 }");
  const auto witnessed =
      test::launch_witnessed("real_time", text, "reference", test::scope_dds_to_this_test());
  RTHS_ASSERT_REAL_TIME_RUN_COMPLETED(witnessed);
  const auto& run = witnessed.run;
  const auto* footer = run.record.footer();
  ASSERT_NE(footer, nullptr);
  EXPECT_GE(footer->wall_seconds(), 0.99);  // 1000 steps of 1 ms cannot finish sooner
  std::uint64_t overruns = 0;
  for (const runtime::StepRecord* s : run.record.steps()) {
    overruns += s->overrun() ? 1 : 0;
    EXPECT_GE(s->lateness(), 0.0);
    for (const runtime::LinkSample& link : s->links()) EXPECT_LE(link.answered_step(), s->step());
  }
  EXPECT_EQ(overruns, footer->counters().overruns());
  EXPECT_EQ(run.record.header()->clock(), "real_time");
}

// Real time with a link slower than dt: each step uses the newest force available and the record
// says which step it answers. An answer is never to a later step; to the same step only when this
// machine stalled the loop for longer than the 6 ms round trip after sending (a busy machine does),
// so the typical answer, not every one, is judged to be 6 steps behind.
TEST_F(DdsRun, RealTimeUsesTheNewestAnswerWhenTheLinkIsSlowerThanAStep) {
  const std::string text = test::paper_frame_study(
      0.6,
      "deployment { clock: REAL_TIME max_overrun_fraction: -1 max_missed_answers: 30 "
      "command_watchdog_periods: 30 nodes { id: 1 kind: SUBSTRUCTURE } "
      "nodes { id: 2 kind: ACTUATOR_EMULATOR receive_lag { one_way_delay: 0.003 } "
      "send_lag { one_way_delay: 0.003 } } }");
  const auto witnessed =
      test::launch_witnessed("slow_link", text, "reference", test::scope_dds_to_this_test());
  RTHS_ASSERT_REAL_TIME_RUN_COMPLETED(witnessed);
  const auto& run = witnessed.run;
  std::vector<double> behind;
  for (const runtime::StepRecord* s : run.record.steps())
    for (const runtime::LinkSample& link : s->links())
      if (link.node_id() == 2 && link.answered_step() > 0) {
        EXPECT_LE(link.answered_step(), s->step());
        behind.push_back(static_cast<double>(s->step() - link.answered_step()));
      }
  ASSERT_GT(behind.size(), 300u);
  // About 6 ms of injected round trip at 1 ms steps, plus the real one.
  EXPECT_GE(runtime::summarize(behind).median, 6.0);
  EXPECT_GT(run.record.footer()->counters().late_feedback(), 300u);
}

// Real time with a wait shorter than any loopback round trip (2 % of a 1 ms step, 20 us): the
// loop stops waiting for both nodes once their answers show it, says so in the record, and the run
// completes on the newest answers.
TEST_F(DdsRun, RealTimeStopsWaitingForAnswersThatCannotComeWithinTheWait) {
  const std::string text = test::paper_frame_study(
      0.6,
      // A window of 100 steps: the test is about the wait, and the one real-time verdict fails a
      // run whose loop overran longer than its window (a stall of this shared machine).
      "deployment { clock: REAL_TIME max_overrun_fraction: -1 max_missed_answers: 100 "
      "command_watchdog_periods: 100 feedback_wait_fraction: 0.02 }");
  const auto witnessed =
      test::launch_witnessed("answer_wait", text, "reference", test::scope_dds_to_this_test());
  RTHS_ASSERT_REAL_TIME_RUN_COMPLETED(witnessed);
  const auto& run = witnessed.run;
  std::vector<std::string> stopped;
  for (const runtime::RecordEntry& e : run.record.entries)
    if (e.has_event() && e.event().what().find("not waiting for the answers of") == 0) {
      stopped.push_back(e.event().what());
      EXPECT_GE(e.event().step(), 64) << "judged on 64 answers: " << e.event().what();
      EXPECT_NE(e.event().what().find("longer than the loop's"), std::string::npos);
    }
  EXPECT_EQ(stopped.size(), 2u) << test::read_file(run.launch.coordinator_log);
}

}  // namespace
}  // namespace rths
