// Records of rths's own distributed runs over Cyclone DDS (real coordinator and node processes on
// loopback, lockstep, DDS domains 220-221), identified from the record: the run is launched with
// effects its config does not declare, then the record's header is given the declared config (as
// a lab's record holds the config it meant to run). Each effect must be named on its own link,
// the clean record name none, and the in-process re-run with the identified model reproduce the
// recorded response where the declared one is far off.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "identify/run_record.h"
#include "runtime/launch.h"
#include "tests/identify/undeclared_run.h"

namespace rths::identify {
namespace {

namespace fs = std::filesystem;
using test::link_effects;

constexpr double kDuration = 5.0;  // s of the paper frame's motion

class DdsRunRecord : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

// A lockstep DDS run of case lag_shift_14ms whose node 1 and node 2 carry `node1` and `node2`
// (NodeSpec fields the declared config lacks); the record's header then holds the declared one.
fs::path launch_with_undeclared(const std::string& name, const std::string& node1,
                                const std::string& node2, int domain) {
  const auto deployment = [&](const std::string& n1, const std::string& n2) {
    return "deployment { nodes { id: 1 kind: SUBSTRUCTURE " + n1 +
           " } nodes { id: 2 kind: ACTUATOR_EMULATOR " + n2 + " } }";
  };
  const auto run = test::launch(name, test::paper_frame_study(kDuration, deployment(node1, node2)),
                                "lag_shift_14ms", domain);
  EXPECT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  const fs::path record = run.dir / "run.rthsrec";
  const config::Study declared =
      test::prepare(test::paper_frame_study(kDuration, deployment("", ""))).config;
  test::rewrite(record, [&](runtime::RecordEntry& e) {
    if (e.has_header()) *e.mutable_header()->mutable_study() = declared;
  });
  return record;
}

IdentifyOptions actuator_only() {
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  return options;
}

TEST_F(DdsRunRecord, ACleanRecordNamesNothingAndReRunsAsRecorded) {
  const RunIdentification run = identify_run_record(
      launch_with_undeclared("identify_dds_clean", "", "", 220), actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(run.held.rfind("complete", 0), 0u) << text;
  EXPECT_TRUE(link_effects(run, 1).empty()) << text;
  EXPECT_TRUE(link_effects(run, 2).empty()) << text;
  ASSERT_EQ(run.actuators.size(), 1u);
  EXPECT_TRUE(run.actuators[0].undeclared.empty()) << text;
  ASSERT_TRUE(run.residual.has_value());
  EXPECT_LT(run.residual->declared, 1e-9) << text;  // lockstep equals in process bit for bit
}

TEST_F(DdsRunRecord, ALagOnOneLinkAndAFirstOrderLagOnTheActuatorAreEachNamedWhereTheyAre) {
  const RunIdentification run = identify_run_record(
      launch_with_undeclared("identify_dds_two", "receive_lag { one_way_delay: 0.001 }",
                             "receive_delay { first_order { time_constant: 0.008 } }", 221),
      actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(link_effects(run, 1), std::set<std::string>{"injection"}) << text;
  EXPECT_TRUE(link_effects(run, 2).empty()) << text;
  ASSERT_EQ(run.actuators.size(), 1u);
  EXPECT_EQ(
      std::set<std::string>(run.actuators[0].undeclared.begin(), run.actuators[0].undeclared.end()),
      std::set<std::string>{"first_order"})
      << text;
  ASSERT_TRUE(run.residual.has_value());
  std::printf("DDS first order 8 ms + 1 ms lag on node 1: NRMSE declared %.4f -> identified %.6f\n",
              run.residual->declared, run.residual->identified);
  EXPECT_GE(run.residual->declared, 0.20) << text;
  EXPECT_LE(run.residual->identified, 0.02) << text;
}

}  // namespace
}  // namespace rths::identify
