#include "study/case_link.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "study/study.h"

namespace rths::study {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";

// The paper's frame (T = 0.5 s, m = 1000 kg, 5 %) on El Centro's first 8 s, with a damper
// (k 5e4 N/m, c 2e3 N s/m) to the ground at a lab: its force reads the velocity of the drift it
// is driven through, so a command that jumps between steps shows as a force far past the
// reference's.
PreparedStudy damper_frame(const std::string& cases) {
  const std::string text =
      "name: \"damper\" structure { matrices { mass { values: 1000 } stiffness { values: "
      "157913.67 } } damping { modal_zeta: 0.05 } } "
      "motion { path: \"../data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: 8 } "
      "integrator { dt: 0.001 } "
      "substructuring { experimental_dofs { dof: 1 stiffness: 50000 damping: 2000 } } "
      "cases { name: \"reference\" } " +
      cases;
  return prepare_study(parse_study(text, "test"), kConfigs);
}

// 5 ms each way with 1.5 ms jitter (sd) and 2 % loss: answers late, lost, overtaken.
const char* const kJitteredLink =
    "link { to_node { one_way_delay: 0.005 jitter: 0.0015 loss: 0.02 seed: 3 } "
    "from_node { one_way_delay: 0.005 jitter: 0.0015 loss: 0.02 seed: 4 "
    "network { drift_rate: 0.0005 } } }";

double largest_step_change(const core::Mat& history) {
  double largest = 0.0;
  for (Eigen::Index k = 1; k < history.rows(); ++k)
    largest = std::max(largest, (history.row(k) - history.row(k - 1)).cwiseAbs().maxCoeff());
  return largest;
}

core::SimulationResult run_case(const PreparedStudy& prepared, int index) {
  return core::simulate(setup_for_case(prepared, prepared.config.cases(index)), prepared.motion);
}

// The link acts on which answer the integrator uses: the command the damper is driven through is
// the structure's drift, which moves no faster than the lag-free frame's (the link's lag changes
// the response a little, hence 25 %), and its force stays the reference's size. A jitter stage
// on the command (what a case had to use before) moves the specimen in jumps: its force is
// several times the reference's, which is what these bounds catch.
TEST(CaseLink, AJitteredLinkNeverJumpsTheSpecimensCommand) {
  const PreparedStudy prepared = damper_frame(
      std::string("cases { name: \"linked\" ") + kJitteredLink +
      " } cases { name: \"command_jitter\" delay { jitter { mean_delay: 0.01 std_dev: 0.0015 "
      "seed: 3 } } }");
  const core::SimulationResult reference = run_case(prepared, 0);
  const core::SimulationResult linked = run_case(prepared, 1);
  const core::SimulationResult jittered = run_case(prepared, 2);
  ASSERT_FALSE(linked.diverged);
  ASSERT_EQ(linked.steps(), reference.steps());
  const double reference_step = largest_step_change(reference.command);
  const double reference_force = reference.measured_force.cwiseAbs().maxCoeff();
  EXPECT_LE(largest_step_change(linked.command), 1.25 * reference_step);
  EXPECT_LE(linked.measured_force.cwiseAbs().maxCoeff(), 1.25 * reference_force);
  EXPECT_GT(jittered.measured_force.cwiseAbs().maxCoeff(), 2.0 * reference_force);
  // What the link did shows in the response against the reference: not nothing, not a blow-up.
  const double peak = reference.displacement.cwiseAbs().maxCoeff();
  const double difference = (linked.displacement - reference.displacement).cwiseAbs().maxCoeff();
  EXPECT_GT(difference, 1e-3 * peak);
  EXPECT_LT(difference, 0.3 * peak);
}

TEST(CaseLink, OneLinkServesEveryActuatorAndFieldsCarryOver) {
  const PreparedStudy prepared =
      damper_frame(std::string("cases { name: \"linked\" ") + kJitteredLink + " }");
  const core::HybridSetup setup = setup_for_case(prepared, prepared.config.cases(1));
  ASSERT_EQ(setup.links.size(), 1u);
  EXPECT_EQ(setup.links[0].to_node.one_way_delay, 0.005);
  EXPECT_EQ(setup.links[0].to_node.seed, 3u);
  EXPECT_EQ(setup.links[0].from_node.loss, 0.02);
  EXPECT_EQ(setup.links[0].from_node.drift_rate, 0.0005);
  EXPECT_TRUE(setup_for_case(prepared, prepared.config.cases(0)).links.empty());
}

// The lag a case's check weighs is its chain's and its link's round trip together, and its delay
// column says both: a link of 30 ms each way behind a 14 ms actuator is 74 ms.
TEST(CaseLink, TheCasesLagAndDelayTextHoldTheLinksRoundTrip) {
  const PreparedStudy prepared = damper_frame(
      "cases { name: \"sites\" delay { shift { delay: 0.014 } } link { to_node { one_way_delay: "
      "0.030 jitter: 0.0025 loss: 0.01 } from_node { one_way_delay: 0.030 jitter: 0.0025 loss: "
      "0.01 } } }");
  const core::HybridSetup setup = setup_for_case(prepared, prepared.config.cases(1));
  EXPECT_NEAR(answer_lag(setup), 0.074, 1e-12);
  EXPECT_EQ(case_delay_text(setup), "shift(14 ms); link 30 ms, jitter 2.5 ms, loss 1 % each way");
  const core::HybridSetup reference = setup_for_case(prepared, prepared.config.cases(0));
  EXPECT_EQ(answer_lag(reference), 0.0);
  EXPECT_EQ(case_delay_text(reference), "none");
}

TEST(CaseLink, TooManyLinksForTheActuatorsAreRefusedWithBothCounts) {
  const PreparedStudy prepared =
      damper_frame("cases { name: \"two\" link {} link { to_node { one_way_delay: 0.01 } } }");
  try {
    setup_for_case(prepared, prepared.config.cases(1));
    FAIL() << "two links for one actuator were taken";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("case 'two' link: 2 link blocks for 1 actuators"), std::string::npos)
        << what;
  }
}

TEST(CaseLink, ALossOutsideItsRangeNamesTheField) {
  try {
    damper_frame("cases { name: \"lossy\" link { from_node { loss: 1.5 } } }");
    FAIL() << "a loss of 1.5 was taken";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cases[1] 'lossy' link[0].from_node.loss = 1.5 is outside [0, 1)"),
              std::string::npos)
        << what;
  }
}

}  // namespace
}  // namespace rths::study
