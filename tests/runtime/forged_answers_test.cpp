// Strangers that answer as a node, on real processes over Cyclone DDS (the shared domain, each test
// on topics of its own): tests/support's rths_rogue forging node 1's answers (an integrity fault
// stops the run), its forgeries before the coordinator pins node 1 and its byte-for-byte replays
// (dropped unread under a run secret).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fault_cluster.h"
#include "tests/support/dds_scope.h"
#include "transport/topic_scope.h"

namespace rths {
namespace {

using util::ChildProcess;
using namespace std::chrono_literals;
using namespace faults;

// A stranger that answers as node 1 (copying the run id and the command's stamp off the wire):
// at every 100th step, at every step, or at step 1 from before its command. Every trial must
// stop with an integrity fault naming node 1, never `completed`.
class ForgedAnswers
    : public testing::TestWithParam<std::tuple<const char*, std::vector<std::string>>> {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_P(ForgedAnswers, StopTheRunWithAnIntegrityFaultNamingNode1) {
  const auto& [label, attack] = GetParam();
  const int domain = test::scope_dds_to_this_test();
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
    testing::Values(std::make_tuple("every_100th_step",
                                    std::vector<std::string>{"--mode", "answers", "--every",
                                                             "100"}),
                    std::make_tuple("every_step",
                                    std::vector<std::string>{"--mode", "answers", "--every", "1"}),
                    std::make_tuple("step_1", std::vector<std::string>{"--mode", "first"})),
    [](const auto& info) { return std::string(std::get<0>(info.param)); });

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
    : public testing::TestWithParam<std::tuple<const char*, std::vector<std::string>>> {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_P(EarlyForgery, IsDroppedUnreadAndNeitherStopsTheRunNorBlamesANode) {
  const auto& [label, attack] = GetParam();
  const int domain = test::scope_dds_to_this_test();
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
    testing::Values(
        std::make_tuple("takeover", std::vector<std::string>{"--mode", "takeover", "--every", "1"}),
        std::make_tuple("hold", std::vector<std::string>{"--mode", "hold"}),
        std::make_tuple("error_ready", std::vector<std::string>{"--mode", "error"}),
        std::make_tuple("answers", std::vector<std::string>{"--mode", "answers", "--every", "1"})),
    [](const auto& info) { return std::string(std::get<0>(info.param)); });

// A stranger without the secret replays every genuine message it sees, byte for byte with its
// MAC, from its own writers (rths_rogue --mode replay): the nodes' announcements, answers and
// heartbeats to the coordinator, the coordinator's assignments and commands to the nodes. The MAC
// covers the sending writer's GUID, so each replay fails it where it arrives and is dropped
// unread: the run completes equal to the in-process run (before, a replayed answer stopped it as
// an integrity fault naming node 1), and every side counts the replays unauthenticated, none as
// not entitled.
TEST(Faults, ReplayedGenuineMessagesAreDroppedUnreadAndTheRunCompletes) {
  runtime::ensure_dds_config();
  const int kDomain = test::scope_dds_to_this_test();
  // The run's topics, as its endpoints and the rogue name them under this test's scope.
  const std::string topics = transport::scoped_topic_prefix();
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
  EXPECT_THAT(rogue_log, testing::ContainsRegex("replayed " + topics + "_node1_up kind 5: [1-9]"))
      << rogue_log;
  EXPECT_THAT(rogue_log,
              testing::ContainsRegex("replayed " + topics + "_node1_down kind 4: [1-9]"));
  EXPECT_THAT(rogue_log,
              testing::ContainsRegex("replayed " + topics + "_node2_down kind 4: [1-9]"));
  const auto record = runtime::read_record(c.record);
  ASSERT_NE(record.footer(), nullptr) << log;
  EXPECT_EQ(record.footer()->status(), "completed") << log;
  test::expect_record_equals(record, test::reference_result(text, "lag_shift_14ms"));
  EXPECT_GT(record.footer()->counters().unauthenticated(), 0u);
  EXPECT_EQ(record.footer()->counters().not_entitled(), 0u);
  expect_each_node_counted_unauthenticated(*record.footer(), log);
}

}  // namespace
}  // namespace rths
