// Strangers that publish other than answers on a run's topics, on real processes over Cyclone DDS
// (the shared domain, each test on topics of its own): a junk publisher, and tests/support's
// rths_rogue forging control messages with and without a run secret. Everything is rejected or
// dropped and counted, and the run is unchanged.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fault_cluster.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

using util::ChildProcess;
using namespace std::chrono_literals;
using namespace faults;

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
  const int kDomain = test::scope_dds_to_this_test();
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

// A stranger sends HOLD, STOP, ASSIGN, COMMAND as the coordinator (addressed and broadcast),
// HOLD and ANNOUNCE as node 2 (and node 1's id on node 2's topic), garbage, another run's and
// replayed messages, all through a lockstep run. Everything is rejected and counted, by the
// coordinator and by each node, and the run equals the in-process run bit for bit.
TEST(Faults, ForgedControlMessagesAreRejectedCountedAndChangeNothing) {
  runtime::ensure_dds_config();
  const int kDomain = test::scope_dds_to_this_test();
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

// With a run secret, the control forgeries (rths_rogue --mode control: HOLD, STOP, ASSIGN and
// COMMAND as the coordinator on each node's own command topic, through the run) carry no MAC:
// each node drops them unread, reports how many in its heartbeats, and the record's footer and
// the coordinator's summary name each node's count. The run completes unchanged.
TEST(Faults, ANodesUnauthenticatedDropsReachTheRecordAndTheSummary) {
  runtime::ensure_dds_config();
  const int kDomain = test::scope_dds_to_this_test();
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

}  // namespace
}  // namespace rths
