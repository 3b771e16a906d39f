// Faults on real processes over Cyclone DDS (domains 20-29, 53, 80-86, 90, 160-164 and 187-188): a
// node killed or stalled mid-run, the coordinator killed, a node that never comes or comes late,
// hostile participants (a junk publisher, and tests/support's rths_rogue forging answers and
// control messages), and a disk that fills up under the run record.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iostream>
#include <thread>

#include "rths/proto/runtime.pb.h"
#include "runtime/node/schema.h"
#include "security/run_secret.h"
#include "test_support.h"
#include "tests/support/platform_gate.h"
#include "tests/support/real_time_run.h"
#include "transport/dds_endpoint.h"

namespace rths {
namespace {

using util::ChildProcess;
using namespace std::chrono_literals;

struct Cluster {
  std::filesystem::path dir, record;
  std::vector<util::ChildProcess> nodes;
  std::optional<util::ChildProcess> coordinator;
};

// How the processes of a cluster recognise each other: with a run secret (each process gets
// --secret-file of one made as `rths pki secret` makes it), or --insecure (the writer pinning
// alone, as before run secrets).
enum class Trust { kInsecure, kSecret };

// Arguments that hand a process the cluster's trust; makes the secret file in `dir` once.
std::vector<std::string> trust_arguments(Trust trust, const std::filesystem::path& dir) {
  if (trust == Trust::kInsecure) return {"--insecure"};
  const auto file = dir / "run.secret";
  if (!std::filesystem::exists(file))
    security::write_run_secret_file(file, security::generate_run_secret());
  return {"--secret-file", file.string()};
}

// Starts the listed nodes (id, kind) and the coordinator for `text` (started as
// `coordinator_options` says).
Cluster start(const std::string& name, const std::string& text, int domain,
              const std::vector<std::pair<int, bool>>& nodes, const std::string& case_name,
              const util::ChildOptions& coordinator_options = {}, Trust trust = Trust::kInsecure,
              const std::function<void()>& before_coordinator = {}) {
  Cluster c;
  c.dir = test::scratch_dir(name);
  const auto config = test::write_config(c.dir, text);
  c.record = c.dir / "run.rthsrec";
  const std::vector<std::string> trusted = trust_arguments(trust, c.dir);
  for (const auto& [id, substructure] : nodes) {
    std::vector<std::string> args{
        "--node-id", std::to_string(id), "--domain", std::to_string(domain), "--run-id", name};
    args.insert(args.end(), trusted.begin(), trusted.end());
    c.nodes.emplace_back(substructure
                             ? test::program("rths-substructure-node", "substructure_nodes")
                             : test::program("rths-actuator-emulator", "actuator_emulator"),
                         args, c.dir / ("node_" + std::to_string(id) + ".log"));
  }
  std::vector<std::string> args{"--config",
                                config.string(),
                                "--run-id",
                                name,
                                "--domain",
                                std::to_string(domain),
                                "--record",
                                c.record.string(),
                                "--case",
                                case_name,
                                "--platform-seconds",
                                "0",
                                "--accept-platform"};
  args.insert(args.end(), trusted.begin(), trusted.end());
  if (before_coordinator) before_coordinator();
  c.coordinator.emplace(test::program("rths-coordinator", "coordinator"), args,
                        c.dir / "coordinator.log", coordinator_options);
  return c;
}

// Steps 0..n-1 with no gap, as a record cut at a failure must be.
void expect_contiguous(const runtime::RecordContents& record) {
  const auto steps = record.steps();
  for (std::size_t k = 0; k < steps.size(); ++k) ASSERT_EQ(steps[k]->step(), static_cast<long>(k));
}

// The fail-safe's step counts are widened from 3 to tolerate this shared, loaded test machine
// (a healthy node must not trip them); the mechanism is the same. Deadline misses are not what
// these tests judge.
const std::string kRealTime =
    "deployment { clock: REAL_TIME liveliness_timeout: 0.3 heartbeat_period: 0.02 "
    "max_missed_answers: 30 command_watchdog_periods: 30 max_overrun_fraction: -1 }";

class KillNode : public testing::TestWithParam<std::tuple<int, int, const char*>> {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_P(KillNode, CoordinatorStopsHoldsAndKeepsTheRecordUpToTheFailure) {
  const auto [victim, sig, label] = GetParam();
  const int domain = 20 + victim + (sig == SIGSTOP ? 2 : 0);
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
  Cluster c = start("own_stall", text, 53, {{1, true}, {2, false}}, "reference");
  ASSERT_TRUE(test::wait_for_steps(c.record, 300)) << "the run never reached step 300";
  for (int i = 0; i < 15; ++i) {
    c.nodes[1].signal(SIGSTOP);
    std::this_thread::sleep_for(30ms);
    c.nodes[1].signal(SIGCONT);
    std::this_thread::sleep_for(100ms);
  }
  const auto code = c.coordinator->wait_for(20s);
  const test::MeasuredPlatform during = witness.finish();
  ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
  const runtime::RecordContents record = runtime::read_record(c.record);
  ASSERT_NE(record.header(), nullptr);
  ASSERT_NE(record.footer(), nullptr);
  const std::string& status = record.footer()->status();
  // This test judges the watchdog, not this machine's deadlines (max_overrun_fraction: -1). A run
  // that completed every step but overran more than half of them still fails the deadline
  // verdict, rightly, as under a loaded suite; here that verdict is reported, not judged.
  const bool deadlines_only = *code != 0 && status.rfind("completed with deadline misses", 0) == 0;
  // The watchdog tripping is what this test guards against: that failure is never put down to
  // the machine (the watchdog's own grace is what keeps the node's stall from being read as the
  // coordinator's silence). Any other failure is, only by the suite's one rule
  // (tests/support/real_time_run.h): a stall of half the window it passed, the machine measured
  // before and after the run.
  const std::string node_log = test::read_file(c.dir / "node_2.log");
  const bool watchdog_tripped = status.find("command watchdog") != std::string::npos ||
                                node_log.find("command watchdog") != std::string::npos;
  if (*code != 0 && !deadlines_only && !watchdog_tripped)
    if (const auto why = test::machine_stalled(status, *record.header(), during))
      GTEST_SKIP() << *why;
  EXPECT_FALSE(watchdog_tripped) << status << "\n" << node_log;
  if (deadlines_only) {
    std::printf("the deadline verdict, not judged here: %s (the machine: %s)\n", status.c_str(),
                during.text.c_str());
    EXPECT_EQ(record.steps().size(), 6000u) << status;  // every step of the 6 s run
  } else {
    EXPECT_EQ(*code, 0) << test::read_file(c.dir / "coordinator.log");
  }
}

TEST(Faults, KilledCoordinatorLeavesAReadableRecordAndTheNodesLeave) {
  runtime::ensure_dds_config();
  // The nodes' answers are not what this test judges: a window of 200 steps keeps a node that a
  // loaded machine holds back for 65 ms (its answers that old, never applied) from stopping the
  // run before the coordinator is killed.
  std::string deployment = kRealTime;
  deployment.replace(deployment.find("max_missed_answers: 30"), 22, "max_missed_answers: 200");
  const std::string text = test::paper_frame_study(8, deployment);
  Cluster c = start("kill_coordinator", text, 25, {{1, true}, {2, false}}, "reference");
  ASSERT_TRUE(test::wait_for_steps(c.record, 300)) << "the run never reached step 300";
  c.coordinator->signal(SIGKILL);
  EXPECT_EQ(c.coordinator->wait(), 128 + SIGKILL);
  for (auto& node : c.nodes) {
    const auto code = node.wait_for(6s);  // orphan timeout max(2, 2 x 0.3) s
    ASSERT_TRUE(code.has_value()) << node.name() << " outlived its coordinator";
    EXPECT_EQ(*code, 1);
  }
  // The emulator held on its own watchdog long before its orphan timeout.
  EXPECT_NE(test::read_file(c.dir / "node_2.log").find("command watchdog"), std::string::npos)
      << test::read_file(c.dir / "node_2.log");
  const auto record = runtime::read_record(c.record);
  EXPECT_EQ(record.footer(), nullptr);
  expect_contiguous(record);
  EXPECT_GE(record.steps().size(), 300u);
}

TEST(Faults, StartUpTimeoutNamesTheMissingNode) {
  runtime::ensure_dds_config();
  const std::string text = test::paper_frame_study(1, "deployment { start_timeout: 1 }");
  Cluster c = start("missing_node", text, 26, {{1, true}}, "reference");
  const auto code = c.coordinator->wait_for(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 1);
  const std::string log = test::read_file(c.dir / "coordinator.log");
  EXPECT_NE(log.find("node 2 (actuator emulator) never announced"), std::string::npos) << log;
  EXPECT_EQ(log.find("node 1 (substructure) never"), std::string::npos) << log;
  EXPECT_EQ(c.nodes[0].wait_for(5s).value_or(-1), 0);  // stopped, not orphaned
}

// Publishes junk both ways until told to stop: another run's messages, garbage, unknown kinds
// and nodes, and commands to the nodes from a stranger (never an answer of this run: that is a
// forgery, see ForgedAnswers).
void hostile(int domain, const std::string& run_id, std::atomic<bool>& stop,
             std::atomic<int>& sent) {
  transport::DdsEndpointOptions as_coordinator{static_cast<std::uint32_t>(domain), true, 0};
  transport::DdsEndpointOptions as_node{static_cast<std::uint32_t>(domain), false, 1};
  transport::DdsEndpoint down(as_coordinator), up(as_node);
  runtime::Command command;
  command.set_time(0.001);
  command.add_drift(1.0);
  command.add_drift_velocity(1.0);
  runtime::Feedback feedback;
  feedback.add_force(1e9);
  feedback.add_realised(1.0);
  while (!stop) {
    for (int node : {1, 2}) {
      // To the nodes: another run's command, garbage bytes, a replay of step 0, a far future step.
      down.send(runtime::pack("someone-else", node, runtime::COMMAND, 5, command));
      auto garbage = runtime::pack(run_id, node, runtime::COMMAND, 1, command);
      garbage.payload = "\xff\xff\xff\xff not protobuf";
      garbage.step = 1'000'000'000;
      down.send(garbage);
      down.send(runtime::pack(run_id, node, runtime::COMMAND, 0, command));
      down.send(runtime::pack(run_id, node, runtime::COMMAND, 0, command));
      // To the coordinator: foreign run, unknown kind, unknown node, node 2's id on node 1's topic.
      up.send(runtime::pack("someone-else", node, runtime::FEEDBACK, 3, feedback));
      auto unknown_kind = runtime::pack(run_id, node, runtime::FEEDBACK, 3, feedback);
      unknown_kind.kind = 77;
      up.send(unknown_kind);
      up.send(runtime::pack(run_id, 42, runtime::HEARTBEAT, 3, runtime::Heartbeat{}));
      up.send(runtime::pack(run_id, 2, runtime::FEEDBACK, 1'000'000'000, feedback));
      sent += 8;
    }
    std::this_thread::sleep_for(2ms);
  }
}

TEST(Faults, HostileParticipantChangesNothingAndIsCounted) {
  runtime::ensure_dds_config();
  constexpr int kDomain = 27;
  const std::string name = "hostile";
  const std::string text = test::paper_frame_study(6, "");
  std::atomic<bool> stop{false};
  std::atomic<int> sent{0};
  std::thread attacker([&] { hostile(kDomain, name, stop, sent); });
  std::this_thread::sleep_for(200ms);  // already publishing when the run starts
  Cluster c = start(name, text, kDomain, {{1, true}, {2, false}}, "lag_shift_14ms");
  const auto code = c.coordinator->wait_for(60s);
  stop = true;
  attacker.join();
  ASSERT_TRUE(code.has_value());
  ASSERT_EQ(*code, 0) << test::read_file(c.dir / "coordinator.log");
  EXPECT_GT(sent.load(), 100);
  const auto record = runtime::read_record(c.record);
  test::expect_record_equals(record, test::reference_result(text, "lag_shift_14ms"));
  const auto& counters = record.footer()->counters();
  EXPECT_GT(counters.foreign_run(), 0u);
  EXPECT_GT(counters.garbage(), 0u);
  EXPECT_GT(counters.unknown_node(), 0u);
  EXPECT_GT(counters.not_entitled(), 0u);
  // Each node's rejects reach the record: the stranger's commands were not the coordinator's.
  ASSERT_EQ(record.footer()->node_rejects_size(), 2);
  for (const runtime::NodeRejects& n : record.footer()->node_rejects()) {
    EXPECT_TRUE(n.final()) << n.label();
    EXPECT_GT(n.rejected().not_entitled(), 0u) << n.label();
    EXPECT_GT(n.rejected().foreign_run(), 0u) << n.label();
  }
  for (auto& node : c.nodes) EXPECT_EQ(node.wait_for(5s).value_or(-1), 0);
  // Each node says how many messages it rejected when it stops.
  for (const char* log : {"node_1.log", "node_2.log"}) {
    const std::string text_log = test::read_file(c.dir / log);
    EXPECT_NE(text_log.find("messages rejected"), std::string::npos) << text_log;
    EXPECT_EQ(text_log.find("(0 messages rejected)"), std::string::npos) << text_log;
  }
}

// tests/support/rogue_participant.cpp in `domain` (it learns the run id off the wire).
util::ChildProcess rogue(const std::filesystem::path& log, int domain,
                         std::vector<std::string> attack) {
  std::vector<std::string> args{"--domain", std::to_string(domain), "--seconds", "60"};
  args.insert(args.end(), attack.begin(), attack.end());
  return util::ChildProcess(test::program("rths_rogue", "tests/support"), args, log);
}

// Trials per forgery (RTHS_ROGUE_TRIALS overrides; the README quotes a longer measurement).
int rogue_trials() {
  const char* env = std::getenv("RTHS_ROGUE_TRIALS");
  return env && *env ? std::max(1, std::atoi(env)) : 3;
}

// A stranger that answers as node 1 (copying the run id and the command's stamp off the wire):
// at every 100th step, at every step, or at step 1 from before its command. Every trial must
// stop with an integrity fault naming node 1, never `completed`.
class ForgedAnswers
    : public testing::TestWithParam<std::tuple<const char*, int, std::vector<std::string>>> {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_P(ForgedAnswers, StopTheRunWithAnIntegrityFaultNamingNode1) {
  const auto& [label, domain, attack] = GetParam();
  const std::string text = test::paper_frame_study(2, "");
  const int trials = rogue_trials();
  int faulted = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const std::string name = std::string("forged_") + label + "_" + std::to_string(trial);
    const auto dir = test::scratch_dir(name);
    util::ChildProcess attacker = rogue(dir / "rogue.log", domain, attack);
    Cluster c = start(name, text, domain, {{1, true}, {2, false}}, "lag_shift_14ms");
    const auto code = c.coordinator->wait_for(60s);
    attacker.terminate();
    ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
    const std::string log = test::read_file(c.dir / "coordinator.log");
    const auto record = runtime::read_record(c.record);
    ASSERT_NE(record.footer(), nullptr) << log;
    const runtime::RunFooter& footer = *record.footer();
    EXPECT_EQ(*code, 1) << log;
    EXPECT_NE(footer.status(), "completed");
    EXPECT_THAT(footer.status(), testing::HasSubstr("integrity fault")) << log;
    EXPECT_EQ(footer.failed_node(), "node 1 (substructure)") << footer.status();
    EXPECT_THAT(footer.status(), testing::HasSubstr("arrived at realtime_ns")) << footer.status();
    faulted += *code == 1 && footer.status().find("integrity fault") != std::string::npos &&
                       footer.failed_node() == "node 1 (substructure)"
                   ? 1
                   : 0;
    for (auto& node : c.nodes) node.terminate();
  }
  std::cout << "forged answers (" << label << "): " << faulted << " of " << trials
            << " trials stopped with an integrity fault naming node 1\n";
  EXPECT_EQ(faulted, trials);
}

INSTANTIATE_TEST_SUITE_P(
    Rogue, ForgedAnswers,
    testing::Values(std::make_tuple("every_100th_step", 80,
                                    std::vector<std::string>{"--mode", "answers", "--every",
                                                             "100"}),
                    std::make_tuple("every_step", 81,
                                    std::vector<std::string>{"--mode", "answers", "--every", "1"}),
                    std::make_tuple("step_1", 82, std::vector<std::string>{"--mode", "first"})),
    [](const auto& info) { return std::string(std::get<0>(info.param)); });

// A stranger sends HOLD, STOP, ASSIGN, COMMAND as the coordinator (addressed and broadcast),
// HOLD and ANNOUNCE as node 2 (and node 1's id on node 2's topic), garbage, another run's and
// replayed messages, all through a lockstep run. Everything is rejected and counted, by the
// coordinator and by each node, and the run equals the in-process run bit for bit.
TEST(Faults, ForgedControlMessagesAreRejectedCountedAndChangeNothing) {
  runtime::ensure_dds_config();
  constexpr int kDomain = 83;
  const std::string name = "forged_control";
  const std::string text = test::paper_frame_study(3, "");
  const auto dir = test::scratch_dir(name + "_rogue");
  util::ChildProcess attacker = rogue(dir / "rogue.log", kDomain, {"--mode", "control"});
  Cluster c = start(name, text, kDomain, {{1, true}, {2, false}}, "lag_shift_14ms");
  const auto code = c.coordinator->wait_for(60s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(attacker.wait_for(10s).value_or(-1), 0) << test::read_file(dir / "rogue.log");
  ASSERT_EQ(*code, 0) << test::read_file(c.dir / "coordinator.log");
  const std::string rogue_log = test::read_file(dir / "rogue.log");
  EXPECT_THAT(rogue_log, testing::HasSubstr("HOLD/STOP/ASSIGN/COMMAND as the coordinator"));
  EXPECT_THAT(rogue_log, testing::HasSubstr("replayed command"));
  const auto record = runtime::read_record(c.record);
  test::expect_record_equals(record, test::reference_result(text, "lag_shift_14ms"));
  const runtime::Counters& counters = record.footer()->counters();
  EXPECT_GT(counters.not_entitled(), 0u);
  EXPECT_GT(counters.foreign_run(), 0u);
  EXPECT_GT(counters.garbage(), 0u);
  for (const runtime::NodeRejects& n : record.footer()->node_rejects())
    EXPECT_GT(n.rejected().not_entitled(), 0u) << n.label();
  for (auto& node : c.nodes) EXPECT_EQ(node.wait_for(5s).value_or(-1), 0);
}

// Waits until the rogue says it learned the run id (its log's "run " line).
void wait_for_run_id(const std::filesystem::path& log) {
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (test::read_file(log).rfind("run ", 0) == 0) return;
    std::this_thread::sleep_for(20ms);
  }
  FAIL() << "the rogue never learned the run id: " << test::read_file(log);
}

// A stranger attacks node 1 before the coordinator pins it, in a run with a run secret: it reads
// the run id off node 1's own announcement and, before the coordinator even starts, floods node
// 1's up topic with an ANNOUNCE and READY as node 1 (then an answer to every command), a HOLD, or
// a READY carrying an error. None of it carries a MAC under the secret: every trial completes,
// equal to the in-process run bit for bit, blames nobody, and the record names what was dropped.
class EarlyForgery
    : public testing::TestWithParam<std::tuple<const char*, int, std::vector<std::string>>> {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_P(EarlyForgery, IsDroppedUnreadAndNeitherStopsTheRunNorBlamesANode) {
  const auto& [label, domain, attack] = GetParam();
  const std::string text = test::paper_frame_study(1, "");
  const core::SimulationResult reference = test::reference_result(text, "lag_shift_14ms");
  const int trials = rogue_trials();
  int completed = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const std::string name = std::string("early_") + label + "_" + std::to_string(trial);
    const auto dir = test::scratch_dir(name + "_rogue");
    util::ChildProcess attacker = rogue(dir / "rogue.log", domain, attack);
    // Early attacks start before the coordinator; answers need its commands to answer.
    const bool early = std::string(label) != "answers";
    Cluster c = start(name, text, domain, {{1, true}, {2, false}}, "lag_shift_14ms", {},
                      Trust::kSecret, [&] {
                        if (early) wait_for_run_id(dir / "rogue.log");
                      });
    const auto code = c.coordinator->wait_for(60s);
    attacker.terminate();
    ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
    const std::string log = test::read_file(c.dir / "coordinator.log");
    const std::string rogue_log = test::read_file(dir / "rogue.log");
    EXPECT_THAT(rogue_log, testing::ContainsRegex("sent [1-9]")) << rogue_log;
    EXPECT_EQ(*code, 0) << log;
    const auto record = runtime::read_record(c.record);
    ASSERT_NE(record.footer(), nullptr) << log;
    EXPECT_EQ(record.footer()->status(), "completed") << log;
    EXPECT_EQ(record.footer()->failed_node(), "") << record.footer()->status();
    test::expect_record_equals(record, reference);
    EXPECT_THAT(log, testing::HasSubstr("dropped unread; newest: kind ")) << log;
    bool named = false;
    for (const runtime::RecordEntry& entry : record.entries)
      named = named ||
              (entry.has_event() &&
               entry.event().what().find("dropped unread as unauthenticated") != std::string::npos);
    EXPECT_TRUE(named) << "no record event names the unauthenticated messages";
    // And the footer counts them, so `rths export` and the summaries show the flood.
    EXPECT_GT(record.footer()->counters().unauthenticated(), 0u);
    completed += *code == 0 && record.footer()->status() == "completed" ? 1 : 0;
    for (auto& node : c.nodes) EXPECT_EQ(node.wait_for(5s).value_or(-1), 0);
  }
  std::cout << "early forgery (" << label << "): " << completed << " of " << trials
            << " trials completed unaffected, no node blamed\n";
  EXPECT_EQ(completed, trials);
}

INSTANTIATE_TEST_SUITE_P(
    Rogue, EarlyForgery,
    testing::Values(std::make_tuple("takeover", 160,
                                    std::vector<std::string>{"--mode", "takeover", "--every", "1"}),
                    std::make_tuple("hold", 161, std::vector<std::string>{"--mode", "hold"}),
                    std::make_tuple("error_ready", 162,
                                    std::vector<std::string>{"--mode", "error"}),
                    std::make_tuple("answers", 163,
                                    std::vector<std::string>{"--mode", "answers", "--every", "1"})),
    [](const auto& info) { return std::string(std::get<0>(info.param)); });

// Each node's own unauthenticated drops as the record's footer and the coordinator's summary
// name them (its last heartbeat's, final on STOP): at least one, none counted not entitled.
void expect_each_node_counted_unauthenticated(const runtime::RunFooter& footer,
                                              const std::string& summary) {
  ASSERT_EQ(footer.node_rejects_size(), 2);
  for (const runtime::NodeRejects& n : footer.node_rejects()) {
    EXPECT_TRUE(n.final()) << n.label();
    EXPECT_GT(n.rejected().unauthenticated(), 0u) << n.label();
    EXPECT_EQ(n.rejected().not_entitled(), 0u) << n.label();
    EXPECT_THAT(summary, testing::HasSubstr(n.label() + " DDS messages rejected: ")) << summary;
    EXPECT_THAT(summary, testing::HasSubstr(", unauthenticated " +
                                            std::to_string(n.rejected().unauthenticated()) + "\n"))
        << summary;
  }
}

// A stranger without the secret replays every genuine message it sees, byte for byte with its
// MAC, from its own writers (rths_rogue --mode replay): the nodes' announcements, answers and
// heartbeats to the coordinator, the coordinator's assignments and commands to the nodes. The MAC
// covers the sending writer's GUID, so each replay fails it where it arrives and is dropped
// unread: the run completes equal to the in-process run (before, a replayed answer stopped it as
// an integrity fault naming node 1), and every side counts the replays unauthenticated, none as
// not entitled.
TEST(Faults, ReplayedGenuineMessagesAreDroppedUnreadAndTheRunCompletes) {
  runtime::ensure_dds_config();
  constexpr int kDomain = 187;
  const std::string name = "replayed";
  const std::string text = test::paper_frame_study(2, "");
  const auto dir = test::scratch_dir(name + "_rogue");
  util::ChildProcess attacker = rogue(dir / "rogue.log", kDomain, {"--mode", "replay"});
  std::this_thread::sleep_for(1s);  // discovered before the nodes announce
  Cluster c =
      start(name, text, kDomain, {{1, true}, {2, false}}, "lag_shift_14ms", {}, Trust::kSecret);
  const auto code = c.coordinator->wait_for(60s);
  ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
  for (auto& node : c.nodes) EXPECT_EQ(node.wait_for(5s).value_or(-1), 0) << node.name();
  EXPECT_EQ(attacker.terminate(), 0);
  const std::string log = test::read_file(c.dir / "coordinator.log");
  const std::string rogue_log = test::read_file(dir / "rogue.log");
  ASSERT_EQ(*code, 0) << log << rogue_log;
  // Node 1's answers (FEEDBACK, 5) and the commands to each node (COMMAND, 4) were replayed.
  EXPECT_THAT(rogue_log, testing::ContainsRegex("replayed rths_node1_up kind 5: [1-9]"))
      << rogue_log;
  EXPECT_THAT(rogue_log, testing::ContainsRegex("replayed rths_node1_down kind 4: [1-9]"));
  EXPECT_THAT(rogue_log, testing::ContainsRegex("replayed rths_node2_down kind 4: [1-9]"));
  const auto record = runtime::read_record(c.record);
  ASSERT_NE(record.footer(), nullptr) << log;
  EXPECT_EQ(record.footer()->status(), "completed") << log;
  test::expect_record_equals(record, test::reference_result(text, "lag_shift_14ms"));
  EXPECT_GT(record.footer()->counters().unauthenticated(), 0u);
  EXPECT_EQ(record.footer()->counters().not_entitled(), 0u);
  expect_each_node_counted_unauthenticated(*record.footer(), log);
}

// With a run secret, the control forgeries (rths_rogue --mode control: HOLD, STOP, ASSIGN and
// COMMAND as the coordinator on each node's own command topic, through the run) carry no MAC:
// each node drops them unread, reports how many in its heartbeats, and the record's footer and
// the coordinator's summary name each node's count. The run completes unchanged.
TEST(Faults, ANodesUnauthenticatedDropsReachTheRecordAndTheSummary) {
  runtime::ensure_dds_config();
  constexpr int kDomain = 188;
  const std::string name = "node_unauthenticated";
  const std::string text = test::paper_frame_study(3, "");
  const auto dir = test::scratch_dir(name + "_rogue");
  util::ChildProcess attacker = rogue(dir / "rogue.log", kDomain, {"--mode", "control"});
  Cluster c =
      start(name, text, kDomain, {{1, true}, {2, false}}, "lag_shift_14ms", {}, Trust::kSecret);
  const auto code = c.coordinator->wait_for(60s);
  ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
  for (auto& node : c.nodes) EXPECT_EQ(node.wait_for(5s).value_or(-1), 0) << node.name();
  attacker.terminate();
  const std::string log = test::read_file(c.dir / "coordinator.log");
  const std::string rogue_log = test::read_file(dir / "rogue.log");
  ASSERT_EQ(*code, 0) << log << rogue_log;
  EXPECT_THAT(rogue_log, testing::HasSubstr("HOLD/STOP/ASSIGN/COMMAND as the coordinator: "));
  const auto record = runtime::read_record(c.record);
  ASSERT_NE(record.footer(), nullptr) << log;
  EXPECT_EQ(record.footer()->status(), "completed") << log;
  test::expect_record_equals(record, test::reference_result(text, "lag_shift_14ms"));
  expect_each_node_counted_unauthenticated(*record.footer(), log);
}

// Without a secret, DDS Security or --insecure, a node and the coordinator refuse to start (exit
// 2, before DDS), saying why and how to give one.
TEST(Faults, WithoutASecretOrSecurityTheProgramsRefuseToStart) {
  const auto dir = test::scratch_dir("no_secret");
  const auto config = test::write_config(dir, test::paper_frame_study(0.2, ""));
  util::ChildOptions clean;
  clean.environment = {{security::kSecretEnv, ""}, {security::kSecretFileEnv, ""}};
  util::ChildProcess node(test::program("rths-substructure-node", "substructure_nodes"),
                          {"--node-id", "1", "--domain", "164", "--run-id", "no_secret"},
                          dir / "node.log", clean);
  util::ChildProcess coordinator(test::program("rths-coordinator", "coordinator"),
                                 {"--config", config.string(), "--domain", "164"},
                                 dir / "coordinator.log", clean);
  EXPECT_EQ(node.wait_for(20s).value_or(-1), 2);
  EXPECT_EQ(coordinator.wait_for(20s).value_or(-1), 2);
  for (const char* log : {"node.log", "coordinator.log"}) {
    const std::string text = test::read_file(dir / log);
    EXPECT_THAT(text, testing::HasSubstr("no run secret")) << text;
    EXPECT_THAT(text, testing::HasSubstr("--insecure")) << text;
  }
}

// Node 2 joins 4 s after node 1 (start_timeout 10 s): the run waits for it, node 1 stays
// assigned meanwhile (the start-up heartbeat), and the run completes.
TEST(Faults, ALateJoinerWithinTheStartTimeoutIsWaitedFor) {
  runtime::ensure_dds_config();
  constexpr int kDomain = 84;
  const std::string name = "late_joiner";
  const std::string text = test::paper_frame_study(0.5, "deployment { start_timeout: 10 }");
  Cluster c = start(name, text, kDomain, {{1, true}}, "reference");
  std::this_thread::sleep_for(4s);
  util::ChildProcess late(
      test::program("rths-actuator-emulator", "actuator_emulator"),
      {"--node-id", "2", "--domain", std::to_string(kDomain), "--run-id", name, "--insecure"},
      c.dir / "node_2.log");
  const auto code = c.coordinator->wait_for(30s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 0) << test::read_file(c.dir / "coordinator.log")
                      << test::read_file(c.dir / "node_1.log");
  EXPECT_EQ(c.nodes[0].wait_for(5s).value_or(-1), 0) << test::read_file(c.dir / "node_1.log");
  EXPECT_EQ(late.wait_for(5s).value_or(-1), 0);
}

// The disk fills up under the record of a real-time run: the coordinator's file size is limited
// (prlimit's RLIMIT_FSIZE, as `ulimit -f` would; the coordinator ignores SIGXFSZ itself, so a
// write past it fails with EFBIG as a full disk fails with ENOSPC; no root or mount needed). The
// run stops within 5 steps of the last entry the disk took, holds and stops the nodes, names the
// reason, and the record reads up to there.
TEST(Faults, ARecordThatCannotBeWrittenStopsTheRunWithinFiveSteps) {
  if (!util::tool_available("prlimit")) GTEST_SKIP() << "prlimit (util-linux) is not installed";
  runtime::ensure_dds_config();
  // About 1000 steps of this run's entries (header ~1.3 KB, a step ~190 bytes with two links).
  constexpr std::uintmax_t kLimit = 200'000;
  util::ChildOptions limited;
  limited.prefix = {"sh", "-c",
                    "exec prlimit --fsize=" + std::to_string(kLimit) + " \"$0\" \"$@\""};
  // The nodes' own fail-safes are widened far beyond this loaded machine's stalls: the record is
  // what this test judges, and only the record may stop the run.
  const std::string text = test::paper_frame_study(
      8,
      "deployment { clock: REAL_TIME liveliness_timeout: 5 heartbeat_period: 0.02 "
      "max_missed_answers: 5000 command_watchdog_periods: 5000 max_overrun_fraction: -1 }");
  Cluster c = start("disk_full", text, 90, {{1, true}, {2, false}}, "lag_shift_14ms", limited);
  const auto code = c.coordinator->wait_for(20s);
  ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
  const std::string log = test::read_file(c.dir / "coordinator.log");
  EXPECT_EQ(*code, 3) << "the machine's fault, not the test's: " << log;
  EXPECT_NE(log.find("cannot write run record " + c.record.string() + ": " + std::strerror(EFBIG)),
            std::string::npos)
      << log;
  EXPECT_EQ(std::filesystem::file_size(c.record), kLimit);
  const auto record = runtime::read_record(c.record);
  EXPECT_TRUE(record.truncated);
  EXPECT_FALSE(record.lost_entries()) << record.warning;
  EXPECT_EQ(record.footer(), nullptr);  // the disk took nothing after the failure
  expect_contiguous(record);
  const auto steps = static_cast<long>(record.steps().size());
  EXPECT_GT(steps, 500);
  EXPECT_LT(steps, 2000);
  const std::string marker = "stopped at step ";
  const auto at = log.find(marker);
  ASSERT_NE(at, std::string::npos) << log;
  const long stopped = std::stol(log.substr(at + marker.size()));
  std::cout << "record full at step " << steps - 1 << " (" << record.entries.size()
            << " entries); the coordinator stopped at step " << stopped << "\n";
  EXPECT_GE(stopped, steps - 1);
  EXPECT_LE(stopped - (steps - 1), 5);
  EXPECT_NE(log.find("HOLD sent to the actuator emulators"), std::string::npos) << log;
  for (auto& node : c.nodes) EXPECT_EQ(node.wait_for(5s).value_or(-1), 0) << node.name();
  EXPECT_NE(test::read_file(c.dir / "node_2.log").find("HOLD"), std::string::npos);
}

}  // namespace
}  // namespace rths
