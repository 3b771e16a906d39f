// Faults at start-up on real processes over Cyclone DDS (the shared domain, each test on topics of
// its own): a node that never comes, one that comes late within the start timeout, and programs
// given no run secret.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fault_cluster.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

using util::ChildProcess;
using namespace std::chrono_literals;
using namespace faults;

TEST(Faults, StartUpTimeoutNamesTheMissingNode) {
  runtime::ensure_dds_config();
  const std::string text = test::paper_frame_study(1, "deployment { start_timeout: 1 }");
  Cluster c = start("missing_node", text, test::scope_dds_to_this_test(), {{1, true}}, "reference");
  const auto code = c.coordinator->wait_for(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 1);
  const std::string log = test::read_file(c.dir / "coordinator.log");
  EXPECT_NE(log.find("node 2 (actuator emulator) never announced"), std::string::npos) << log;
  EXPECT_EQ(log.find("node 1 (substructure) never"), std::string::npos) << log;
  EXPECT_EQ(c.nodes[0].wait_for(5s).value_or(-1), 0);  // stopped, not orphaned
}

// Without a secret, DDS Security or --insecure, a node and the coordinator refuse to start (exit
// 2, before DDS), saying why and how to give one.
TEST(Faults, WithoutASecretOrSecurityTheProgramsRefuseToStart) {
  const auto dir = test::scratch_dir("no_secret");
  const std::string domain = std::to_string(test::scope_dds_to_this_test());
  const auto config = test::write_config(dir, test::paper_frame_study(0.2, ""));
  util::ChildOptions clean;
  clean.environment = {{security::kSecretEnv, ""}, {security::kSecretFileEnv, ""}};
  util::ChildProcess node(test::program("rths-substructure-node", "substructure_nodes"),
                          {"--node-id", "1", "--domain", domain, "--run-id", "no_secret"},
                          dir / "node.log", clean);
  util::ChildProcess coordinator(test::program("rths-coordinator", "coordinator"),
                                 {"--config", config.string(), "--domain", domain},
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
  const int kDomain = test::scope_dds_to_this_test();
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

}  // namespace
}  // namespace rths
