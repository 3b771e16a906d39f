// A node lost mid-run on real processes over Cyclone DDS (the shared domain, each test on topics
// of its own): killed or stopped, the coordinator stops, holds and keeps the record up to the
// failure; the emulator's own short stalls do not trip its command watchdog.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <regex>
#include <vector>

#include "fault_cluster.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

using util::ChildProcess;
using namespace std::chrono_literals;
using namespace faults;

class KillNode : public testing::TestWithParam<std::tuple<int, int, const char*>> {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_P(KillNode, CoordinatorStopsHoldsAndKeepsTheRecordUpToTheFailure) {
  const auto [victim, sig, label] = GetParam();
  const int domain = test::scope_dds_to_this_test();
  const std::string name = "kill_" + std::to_string(victim) + "_" + std::to_string(sig);
  const std::string text = test::paper_frame_study(8, kRealTime);
  Cluster c = start(name, text, domain, {{1, true}, {2, false}}, "lag_shift_14ms");
  ASSERT_TRUE(test::wait_for_steps(c.record, 300)) << "the run never reached step 300";
  test::StallWitness witness;
  const auto killed_at = std::chrono::steady_clock::now();
  const std::int64_t killed_ns = transport::realtime_ns();
  c.nodes[victim - 1].signal(sig);
  const auto code = c.coordinator->wait_for(30s);
  ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
  const double stop_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count();
  const test::MeasuredPlatform machine = witness.finish();
  EXPECT_EQ(*code, 1);
  const std::string log = test::read_file(c.dir / "coordinator.log");
  EXPECT_NE(log.find(label), std::string::npos) << log;
  EXPECT_NE(log.find("consecutive steps"), std::string::npos) << log;
  const auto record = runtime::read_record(c.record);
  ASSERT_NE(record.header(), nullptr);
  // The process may linger up to ~1 s on exit (DDS writer linger towards a dead reader); the
  // HOLD goes out at the stop, which must come within the missed-answer window, not liveliness
  // (the record's HOLD event, below). The exit's 2.5 s is judged on a machine that can pace the
  // loop (real_time_run.h's rule): on a loaded machine the DDS teardown after the logged stop
  // takes seconds more; a hang fails either way.
  if (test::machine_can_pace(machine, record.header()->dt()))
    EXPECT_LT(stop_seconds, 2.5) << machine.text;
  else
    std::cout << "exit " << stop_seconds << " s after the kill, not judged: " << machine.text
              << "\n";
  ASSERT_NE(record.footer(), nullptr);
  EXPECT_FALSE(record.footer()->ok());
  EXPECT_EQ(record.footer()->failed_node(), label);
  expect_contiguous(record);
  EXPECT_GE(record.steps().size(), 300u);
  EXPECT_LT(record.steps().size(), 8000u);
  bool hold = false;
  for (const auto& e : record.entries)
    if (e.has_event() && e.event().what().find("HOLD") == 0) {
      hold = true;
      // 30 steps of 1 ms; generous for this loaded machine, far below the 0.3 s liveliness.
      EXPECT_LT(static_cast<double>(e.event().realtime_ns() - killed_ns) * 1e-9, 0.2);
    }
  EXPECT_TRUE(hold);
  // The survivor leaves on STOP; the emulator, when it survived, logged the HOLD first.
  const int survivor = victim == 1 ? 2 : 1;
  const auto survivor_code = c.nodes[survivor - 1].wait_for(5s);
  ASSERT_TRUE(survivor_code.has_value());
  EXPECT_EQ(*survivor_code, 0);
  if (survivor == 2)
    EXPECT_NE(test::read_file(c.dir / "node_2.log").find("HOLD"), std::string::npos);
  c.nodes[victim - 1].signal(SIGKILL);
}

INSTANTIATE_TEST_SUITE_P(Nodes, KillNode,
                         testing::Values(std::make_tuple(1, SIGKILL, "node 1 (substructure)"),
                                         std::make_tuple(2, SIGKILL, "node 2 (actuator emulator)"),
                                         std::make_tuple(2, SIGSTOP, "node 2 (actuator emulator)")),
                         [](const auto& info) {
                           return std::string(std::get<1>(info.param) == SIGSTOP ? "stall_"
                                                                                 : "kill_") +
                                  std::to_string(std::get<0>(info.param));
                         });

// CLOCK_REALTIME now, ns: the clock the node's hold message stamps (realtime_ns).
std::int64_t realtime_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// An interval of CLOCK_REALTIME, ns.
struct Span {
  std::int64_t from = 0, to = 0;
};

// Stops the emulator (node 2) for 30 ms, 15 times, 100 ms apart; each stop's span (SIGSTOP to
// SIGCONT).
std::vector<Span> stall_the_emulator(Cluster& c) {
  std::vector<Span> stopped;
  for (int i = 0; i < 15; ++i) {
    Span& span = stopped.emplace_back();
    span.from = realtime_ns();
    c.nodes[1].signal(SIGSTOP);
    std::this_thread::sleep_for(30ms);
    c.nodes[1].signal(SIGCONT);
    span.to = realtime_ns();
    std::this_thread::sleep_for(100ms);
  }
  return stopped;
}

// Whether the node's watchdog judged a silence that overlapped one of its own stops: its log's
// "holding on its own at step N (realtime_ns T): command watchdog: no fresh command for X ms"
// names the silence [T - X, T]. One that lay wholly while the node ran was the coordinator's
// silence (the machine's stall, as for any window), not the node's own stall; a hold the log
// does not stamp counts as overlapping.
bool silence_overlaps_a_stop(const std::string& node_log, const std::vector<Span>& stopped) {
  static const std::regex hold(
      "realtime_ns ([0-9]+)\\): command watchdog: no fresh command for ([0-9.]+) ms");
  std::smatch match;
  if (!std::regex_search(node_log, match, hold)) return true;
  const std::int64_t end = std::stoll(match[1].str());
  const std::int64_t begin = end - static_cast<std::int64_t>(std::stod(match[2].str()) * 1e6);
  for (const Span& span : stopped)
    if (begin <= span.to && span.from <= end) return true;
  return false;
}

// The emulator's own process stalled (SIGSTOP for 30 ms, 15 times) is not a silent coordinator:
// the commands that waited on its socket are delivered before its watchdog judges, so it does
// not hold, and the run completes. The watchdog must be shorter than the stall (else the test
// proves nothing) and longer than the machine's own gaps between commands, which are measured
// first: twice the longest wake-up stall, at least 15 periods, at most 25 (a 30 ms stall).
TEST(Faults, TheEmulatorsOwnStallDoesNotTripItsCommandWatchdog) {
  constexpr int kLongestWatchdogPeriods = 25;  // of 1 ms, under the 30 ms stall
  const test::MeasuredPlatform machine = test::measure_platform(1000.0, 1.0);
  const int watchdog = std::max(15, static_cast<int>(std::ceil(2.0 * machine.max / 1e-3)));
  if (watchdog > kLongestWatchdogPeriods)
    GTEST_SKIP() << "this machine stalls too long now to tell a 30 ms stall from its own gaps ("
                 << machine.text << "; the watchdog would need " << watchdog << " ms)";
  runtime::ensure_dds_config();
  const std::string text = test::paper_frame_study(
      6,
      "deployment { clock: REAL_TIME liveliness_timeout: 0.5 heartbeat_period: 0.02 "
      "max_missed_answers: 120 command_watchdog_periods: " +
          std::to_string(watchdog) + " max_overrun_fraction: -1 }");
  test::StallWitness witness;
  Cluster c = start("own_stall", text, test::scope_dds_to_this_test(), {{1, true}, {2, false}},
                    "reference");
  ASSERT_TRUE(test::wait_for_steps(c.record, 300)) << "the run never reached step 300";
  const std::vector<Span> stopped = stall_the_emulator(c);
  const auto code = c.coordinator->wait_for(20s);
  const test::MeasuredPlatform during = witness.finish();
  ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
  const runtime::RecordContents record = runtime::read_record(c.record);
  ASSERT_NE(record.header(), nullptr);
  ASSERT_NE(record.footer(), nullptr);
  const std::string& status = record.footer()->status();
  const std::string coordinator_log = test::read_file(c.dir / "coordinator.log");
  // The loop's CPU time per step is the code's, whatever the machine: never skipped.
  if (const auto why = test::loop_cpu_over_bound(coordinator_log)) FAIL() << *why;
  // This test judges the watchdog, not this machine's deadlines (max_overrun_fraction: -1). A run
  // that completed every step but overran more than half of them still fails the deadline
  // verdict, rightly, as under a loaded suite; here that verdict is reported, not judged.
  const bool deadlines_only = *code != 0 && status.rfind("completed with deadline misses", 0) == 0;
  // The watchdog tripping on a silence that overlapped the node's own stop is what this test
  // guards against: that failure is never put down to the machine (the watchdog's own grace is
  // what keeps the node's stall from being read as the coordinator's silence). Any other failure,
  // a trip on a silence wholly while the node ran included, is the machine's only by the suite's
  // rule (tests/support/real_time_run.h): a stall of half the window it passed, or a loaded
  // machine, measured before and after the run.
  const std::string node_log = test::read_file(c.dir / "node_2.log");
  const bool watchdog_tripped = status.find("command watchdog") != std::string::npos ||
                                node_log.find("command watchdog") != std::string::npos;
  const bool own_stall_tripped = watchdog_tripped && silence_overlaps_a_stop(node_log, stopped);
  if (*code != 0 && !deadlines_only && !own_stall_tripped)
    if (const auto why = test::machine_stalled(status, *record.header(), during))
      GTEST_SKIP() << *why;
  EXPECT_FALSE(watchdog_tripped) << status << "\n" << node_log;
  if (deadlines_only) {
    std::printf("the deadline verdict, not judged here: %s (the machine: %s)\n", status.c_str(),
                during.text.c_str());
    EXPECT_EQ(record.steps().size(), 6000u) << status;  // every step of the 6 s run
  } else {
    EXPECT_EQ(*code, 0) << coordinator_log;
  }
}

}  // namespace
}  // namespace rths
