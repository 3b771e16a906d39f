// Sites configs (checked without namespaces) and runs across network-namespace sites with lag
// injected by the nodes (skipped, with the reason, where namespaces are not permitted).
#include "deploy/sites.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "deploy/netns.h"
#include "tests/support/platform_gate.h"

namespace rths::deploy {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";
constexpr double kMs = 1e-3;

// The paper's frame on three sites: coordinator, substructure node 1, actuator emulator 2.
Sites three_sites(int domain, double to_actuator, double from_actuator) {
  const auto text = R"(
    study: "paper_frame.textproto"
    case_name: "reference"
    clock: LOCKSTEP
    duration: 0.1
    timeout: 60
    sites { name: "integrator" node_ids: 0 }
    sites { name: "numerical" node_ids: 1 }
    sites { name: "lab" node_ids: 2 }
    deployment {
      nodes { id: 1 kind: SUBSTRUCTURE }
      nodes { id: 2 kind: ACTUATOR_EMULATOR }
      start_timeout: 20
    })";
  auto sites = parse_sites(text, "three_sites");
  sites.set_domain_id(domain);
  auto* link = sites.add_links();
  link->set_node_id(2);
  link->mutable_to_node()->set_one_way_delay(to_actuator);
  link->mutable_from_node()->set_one_way_delay(from_actuator);
  return sites;
}

std::string error_of(const Sites& sites) {
  try {
    plan_sites(sites, kConfigs, "test.textproto");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(SitesConfig, AppliesLinkLagsAndOverridesToTheStudy) {
  auto sites = three_sites(120, 0.010, 0.004);
  const auto plan = plan_sites(sites, kConfigs, "test.textproto");
  ASSERT_EQ(plan.placements.size(), 3u);
  EXPECT_EQ(plan.placements[0].node_id, 0);
  EXPECT_EQ(plan.placements[0].site, "integrator");
  EXPECT_EQ(plan.placements[2].kind, "actuator_emulator");
  const auto& deployment = plan.study.deployment();
  EXPECT_EQ(deployment.domain_id(), 120);
  EXPECT_EQ(deployment.case_name(), "reference");
  EXPECT_EQ(deployment.clock(), config::Deployment::LOCKSTEP);
  EXPECT_DOUBLE_EQ(plan.study.motion().duration(), 0.1);
  EXPECT_DOUBLE_EQ(deployment.nodes(1).receive_lag().one_way_delay(), 0.010);
  EXPECT_DOUBLE_EQ(deployment.nodes(1).send_lag().one_way_delay(), 0.004);
  EXPECT_DOUBLE_EQ(deployment.nodes(0).receive_lag().one_way_delay(), 0.0);
  EXPECT_TRUE(std::filesystem::path(plan.study.motion().path()).is_absolute());
  EXPECT_TRUE(std::filesystem::exists(plan.study.motion().path()));
}

TEST(SitesConfig, ShippedConfigLoads) {
  const auto plan = load_sites(kConfigs / "sites_paper_frame.textproto");
  EXPECT_EQ(plan.placements.size(), 3u);
  EXPECT_GT(plan.study.deployment().nodes(1).receive_lag().one_way_delay(), 0.0);
}

// The consortium's frame (issue 61): every shipped sites config names its sites and links, and
// its links carry the same draws as the study's in-process link case.
TEST(SitesConfig, TheConsortiumFrameLoadsWithItsSitesAndLinks) {
  const auto plan = load_sites(kConfigs / "sites_consortium_frame.textproto");
  EXPECT_EQ(plan.placements.size(), 3u);  // the coordinator holds the frame: no numerical node
  const auto& deployment = plan.study.deployment();
  EXPECT_EQ(deployment.case_name(), "sites_predicted");
  EXPECT_EQ(deployment.clock(), config::Deployment::REAL_TIME);
  for (int node : {0, 1}) {
    EXPECT_DOUBLE_EQ(deployment.nodes(node).receive_lag().one_way_delay(), 0.030);
    EXPECT_DOUBLE_EQ(deployment.nodes(node).send_lag().jitter(), 0.0025);
    EXPECT_DOUBLE_EQ(deployment.nodes(node).send_lag().loss(), 0.01);
  }
  // In process, one link per actuator in channel order: lab C's column (node 3) first.
  const auto& lab_c = plan.study.cases(1).link(0);
  EXPECT_EQ(lab_c.to_node().seed(), deployment.nodes(1).receive_lag().seed());
  EXPECT_EQ(lab_c.from_node().seed(), deployment.nodes(1).send_lag().seed());
}

TEST(SitesConfig, ErrorsNameTheProblem) {
  auto unplaced = three_sites(120, 0, 0);
  unplaced.mutable_sites(2)->clear_node_ids();
  EXPECT_NE(error_of(unplaced).find("node 2 (actuator_emulator) is not placed"), std::string::npos)
      << error_of(unplaced);

  auto no_coordinator = three_sites(120, 0, 0);
  no_coordinator.mutable_sites(0)->clear_node_ids();
  EXPECT_NE(error_of(no_coordinator).find("coordinator (node 0) is not placed"), std::string::npos);

  auto twice = three_sites(120, 0, 0);
  twice.mutable_sites(1)->add_node_ids(2);
  EXPECT_NE(error_of(twice).find("already placed at site 'numerical'"), std::string::npos)
      << error_of(twice);

  auto unknown = three_sites(120, 0, 0);
  unknown.mutable_sites(1)->add_node_ids(7);
  EXPECT_NE(error_of(unknown).find("node 7, which the study's deployment does not declare"),
            std::string::npos);

  auto negative = three_sites(120, -0.001, 0);
  EXPECT_NE(error_of(negative).find("link to node 2 to_node"), std::string::npos)
      << error_of(negative);

  auto lossy = three_sites(120, 0.001, 0);
  lossy.mutable_links(0)->mutable_to_node()->set_loss(0.01);
  EXPECT_NE(error_of(lossy).find("node 2 has a lag with loss > 0, but the clock is LOCKSTEP"),
            std::string::npos)
      << error_of(lossy);

  auto bad_name = three_sites(120, 0, 0);
  bad_name.mutable_sites(1)->set_name("Lab A");
  EXPECT_NE(error_of(bad_name).find("'Lab A'"), std::string::npos) << error_of(bad_name);

  EXPECT_THROW(parse_sites("sites { nme: \"x\" }", "typo.textproto"), std::invalid_argument);
  try {
    parse_sites("study: \"a\"\nsites { nme: \"x\" }", "typo.textproto");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("typo.textproto:2:"), std::string::npos) << e.what();
  }
}

class SitesRun : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto reason = namespace_support()) GTEST_SKIP() << *reason;
  }
  std::filesystem::path out(const std::string& name) {
    return std::filesystem::path(RTHS_BINARY_DIR) / "test_out" / "deploy" / name;
  }
};

const LinkMeasurement& link_of(const SitesRunResult& result, int node_id) {
  for (const auto& link : result.links) {
    if (link.node_id == node_id) return link;
  }
  throw std::runtime_error("no link to node " + std::to_string(node_id));
}

// Lockstep: every step waits for both answers, so the run's own pace is an independent measure
// of the slowest link's round trip, against which the record's per-message lags are checked.
TEST_F(SitesRun, TenMillisecondsEachWayAddTwentyToTheRoundTripAndTheRecordAgrees) {
  const auto base_plan = plan_sites(three_sites(91, 0.0, 0.0), kConfigs, "base");
  const auto base = run_sites(base_plan, {out("base"), std::nullopt, {}, {}, false});
  ASSERT_TRUE(base.ok) << base.status;
  const auto lag_plan = plan_sites(three_sites(92, 0.010, 0.010), kConfigs, "lag");
  test::StallWitness witness;
  const auto lagged = run_sites(lag_plan, {out("lag_10ms"), std::nullopt, {}, {}, false});
  const test::MeasuredPlatform machine = witness.finish();
  ASSERT_TRUE(lagged.ok) << lagged.status;
  ASSERT_EQ(lagged.steps, base.steps);
  ASSERT_GT(lagged.steps, 50);

  const auto& base_link = link_of(base, 2);
  const auto& link = link_of(lagged, 2);
  const double base_rt = base_link.round_trip.median;
  const double rt = link.round_trip.median;
  std::printf(
      "base round trip median %.3f ms (p99 %.3f), with 10+10 ms: %.3f ms (p99 %.3f); "
      "one-way down/up %.3f/%.3f ms; run pace %.3f ms/step\n",
      base_rt / kMs, base_link.round_trip.p99 / kMs, rt / kMs, link.round_trip.p99 / kMs,
      link.one_way_down.median / kMs, link.one_way_up.median / kMs,
      lagged.record_wall_seconds / lagged.steps / kMs);
  EXPECT_LT(base_rt, 5 * kMs) << "the base round trip across the veth bridge should be small";
  // Each injected delay is released by a timer wake-up at the node, one each way: 2 ms, widened by
  // twice the p99 wake-up lateness this machine showed during the lagged run.
  EXPECT_NEAR(rt - base_rt, 20 * kMs, 2 * kMs + 2 * machine.p99) << machine.text;
  // The record's injected lag is what was asked for, and the measured one-way lags carry it.
  EXPECT_NEAR(link.injected.median, 20 * kMs, 0.1 * kMs);
  EXPECT_NEAR(base_link.injected.median, 0.0, 1e-9);
  // The one-way lags are stamped on the wire (the node takes the command off the wire before its
  // receive delay and stamps the feedback after its send delay): they are the network alone, and
  // wire down + injected + wire up accounts for the whole measured round trip.
  EXPECT_LT(link.one_way_down.median, 5 * kMs);
  EXPECT_LT(link.one_way_up.median, 5 * kMs);
  EXPECT_NEAR(link.one_way_down.median + link.injected.median + link.one_way_up.median, rt,
              2 * kMs);
  // The un-lagged link to the substructure node is unaffected.
  EXPECT_LT(link_of(lagged, 1).round_trip.median, 5 * kMs);
  // Independent check: the run's pace per step is the slowest round trip plus a little: 5 ms, and
  // twice the p99 wake-up lateness this machine showed during it (each step wakes a process per
  // site).
  const double pace = lagged.record_wall_seconds / static_cast<double>(lagged.steps);
  const double slack = 5 * kMs + 2 * machine.p99;
  EXPECT_GE(pace, 0.95 * rt);
  EXPECT_LE(pace, rt + slack);
  // Everything made was removed.
  const auto left = list_namespaces();
  for (const auto& name : lagged.namespaces) {
    EXPECT_EQ(std::count(left.begin(), left.end(), name), 0) << name;
  }
}

TEST_F(SitesRun, AFailedRunStillTearsEverythingDown) {
  // 100 steps at >= 100 ms each cannot finish within the 2 s limit.
  auto sites = three_sites(93, 0.05, 0.05);
  sites.set_timeout(2.0);
  const auto plan = plan_sites(sites, kConfigs, "timeout");
  const auto result = run_sites(plan, {out("timeout"), std::nullopt, {}, {}, false, -1.0, {}});
  EXPECT_FALSE(result.ok);
  EXPECT_NE(result.status.find("timed out"), std::string::npos) << result.status;
  ASSERT_EQ(result.namespaces.size(), 4u);
  const auto left = list_namespaces();
  for (const auto& name : result.namespaces) {
    EXPECT_EQ(std::count(left.begin(), left.end(), name), 0) << name;
  }
}

}  // namespace
}  // namespace rths::deploy
