#include "analysis/study_run.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/study.h"

namespace rths::analysis {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";

// The paper's frame (T = 0.5 s, 5 %, El Centro) with a case list and extras.
core::PreparedStudy frame(double alpha, const std::string& cases, const std::string& extra = "") {
  const std::string text = "name: \"frame\" structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } } "
                           "motion { path: \"motions/RSN175_IMPVALL.H_H-E12140.AT2\" } "
                           "integrator { dt: 0.001 } substructuring { experimental_fraction: " +
                           std::to_string(alpha) + " } " + cases + " " + extra;
  return core::prepare_study(core::parse_study(text, "test"), kConfigs);
}

TEST(StudyRun, ACasePastItsCriticalDelayIsWarnedAndJudgedDiverged) {
  std::vector<std::string> warnings;
  const StudyOutcome outcome = run_study(
      frame(1.0, "cases { name: \"reference\" } cases { name: \"lag_12ms\" delay { shift { delay: 0.012 } } }"),
      {.warn = [&](const std::string& w) { warnings.push_back(w); }});
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("lag_12ms"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("PAST"), std::string::npos) << warnings[0];
  const CaseOutcome& lagged = outcome.cases[1];
  EXPECT_EQ(lagged.status, "diverged") << lagged.status_detail;
  ASSERT_TRUE(lagged.stability.has_value());
  EXPECT_TRUE(lagged.stability->past());
  EXPECT_EQ(outcome.cases[0].status, "completed");
  ASSERT_EQ(outcome.failures(false).size(), 1u);
  EXPECT_TRUE(outcome.failures(true).empty());
}

TEST(StudyRun, ExpectUnstableMakesTheDivergenceMeant) {
  const StudyOutcome outcome = run_study(
      frame(1.0, "cases { name: \"reference\" } cases { name: \"lag_12ms\" expect_unstable: true "
                 "delay { shift { delay: 0.012 } } }"));
  EXPECT_TRUE(outcome.cases[1].diverged());
  EXPECT_TRUE(outcome.failures(false).empty());
}

TEST(StudyRun, TheStablePaperFrameCompletesWithoutWarning) {
  std::vector<std::string> warnings;
  const StudyOutcome outcome = run_study(
      frame(1.0 / 3.0, "cases { name: \"reference\" } cases { name: \"lag_14ms\" delay { shift { delay: 0.014 } } }"),
      {.warn = [&](const std::string& w) { warnings.push_back(w); }});
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(outcome.cases[1].status, "completed");
  EXPECT_GT(outcome.cases[1].comparison.nrmse_pct, 10.0);  // the paper's "wrong" result, in percent
  EXPECT_EQ(outcome.cases[1].comparison.response, "floor 1");
  EXPECT_TRUE(outcome.failures(false).empty());
  EXPECT_EQ(outcome.motion_units, "g");
}

TEST(StudyRun, DeploymentLimitsApplyInProcess) {
  const StudyOutcome outcome = run_study(
      frame(1.0 / 3.0, "cases { name: \"reference\" }", "deployment { limits { max_displacement: 0.005 } }"));
  const CaseOutcome& c = outcome.cases[0];
  EXPECT_EQ(c.status, "limit tripped");
  EXPECT_NE(c.status_detail.find("floor 1"), std::string::npos) << c.status_detail;
  EXPECT_LT(c.simulation.steps(), 39070u);
  EXPECT_LE(c.simulation.displacement.cwiseAbs().maxCoeff(), 0.005);
  EXPECT_EQ(outcome.failures(true).size(), 1u);  // --allow-unstable does not excuse a limit
}

}  // namespace
}  // namespace rths::analysis
