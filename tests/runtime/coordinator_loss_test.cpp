// The coordinator killed mid-run on real processes over Cyclone DDS (the shared domain, on topics
// of its own): the record reads up to there and the nodes leave.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fault_cluster.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

using util::ChildProcess;
using namespace std::chrono_literals;
using namespace faults;

TEST(Faults, KilledCoordinatorLeavesAReadableRecordAndTheNodesLeave) {
  runtime::ensure_dds_config();
  // The nodes' answers are not what this test judges: a window of 200 steps keeps a node that a
  // loaded machine holds back for 65 ms (its answers that old, never applied) from stopping the
  // run before the coordinator is killed.
  std::string deployment = kRealTime;
  deployment.replace(deployment.find("max_missed_answers: 30"), 22, "max_missed_answers: 200");
  const std::string text = test::paper_frame_study(8, deployment);
  Cluster c = start("kill_coordinator", text, test::scope_dds_to_this_test(),
                    {{1, true}, {2, false}}, "reference");
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

}  // namespace
}  // namespace rths
