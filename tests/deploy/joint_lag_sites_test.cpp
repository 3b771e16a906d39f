// The across-sites runner of the joint lag study: it is available exactly when namespaces are,
// and it runs from the study's sites config (read first, so a missing one is named before any
// namespace or process is made). The runs themselves need root and DDS: `rths joint-lag` with
// configs/joint_lag_study.textproto shows them.
#include "deploy/joint_lag_sites.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "deploy/netns.h"

namespace rths::deploy {
namespace {

TEST(JointLagSites, AvailableExactlyWhenNamespacesAre) {
  const analysis::JointLagAcrossSites sites = joint_lag_across_sites();
  ASSERT_TRUE(sites.unavailable && sites.run);
  EXPECT_EQ(sites.unavailable(), namespace_support());
}

TEST(JointLagSites, AMissingSitesConfigIsNamedBeforeAnythingRuns) {
  analysis::JointLagStudy config;
  config.set_study("paper_frame.textproto");
  config.set_sites("no_such_sites.textproto");
  config.add_measured_network_round_trips(0.004);
  config.add_measured_actuator_lags(0.0);
  analysis::JointLagResult result;
  result.output_directory = std::filesystem::temp_directory_path() / "rths_joint_lag_sites_test";
  std::size_t done = 0;
  try {
    joint_lag_across_sites().run(config, std::filesystem::path(RTHS_SOURCE_DIR) / "configs", result,
                                 [&] { ++done; });
    FAIL() << "ran without a sites config";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_sites.textproto"), std::string::npos) << e.what();
  }
  EXPECT_EQ(done, 0u);
  EXPECT_TRUE(result.measured.empty());
}

}  // namespace
}  // namespace rths::deploy
