// The in-process distributed run (coordinator + node services over InProcessTransport) against
// core::simulate(): the same blocks in the same order must give the same doubles.
#include <gtest/gtest.h>

#include "core/simulation.h"
#include "test_support.h"
#include "tests/support/in_process_run.h"

namespace rths {
namespace {

void expect_identical(const core::SimulationResult& a, const core::SimulationResult& b) {
  ASSERT_EQ(a.steps(), b.steps());
  for (std::size_t k = 0; k < a.steps(); ++k) ASSERT_EQ(a.time[k], b.time[k]) << k;
  // Exact equality, not a tolerance: the same operations in the same order.
  EXPECT_TRUE(a.displacement == b.displacement);
  EXPECT_TRUE(a.velocity == b.velocity);
  EXPECT_TRUE(a.acceleration == b.acceleration);
  EXPECT_TRUE(a.command == b.command);
  EXPECT_TRUE(a.realised == b.realised);
  EXPECT_TRUE(a.measured_force == b.measured_force);
}

struct Variant {
  const char* name;
  std::string text;
  std::string case_name;
};

// ctest shows the variant's name, not its bytes.
void PrintTo(const Variant& v, std::ostream* os) {
  *os << v.name << " (case " << v.case_name << ")";
}

class InProcessEqualsSimulate : public testing::TestWithParam<Variant> {};

TEST_P(InProcessEqualsSimulate, BitForBit) {
  const study::PreparedStudy prepared = test::prepare(GetParam().text);
  coordinator::CoordinatorOptions options;
  options.run_id = "in-process";
  options.case_name = GetParam().case_name;
  const coordinator::RunOutcome outcome = coordinator::run_in_process(prepared, options);
  ASSERT_TRUE(outcome.ok) << outcome.status;
  const auto& study_case = study::find_case(prepared.config, GetParam().case_name);
  const core::SimulationResult reference =
      core::simulate(study::setup_for_case(prepared, study_case), prepared.motion);
  expect_identical(outcome.result, reference);
  EXPECT_GT(outcome.result.measured_force.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(outcome.counters.steps(), reference.steps() - 1);
}

const std::string kTwoNodes = "";  // default nodes: 1 substructure, 2 emulator
const std::string kLocalNumerical = "deployment { nodes { id: 5 kind: ACTUATOR_EMULATOR } }";
const std::string kSplit =
    "deployment { nodes { id: 1 kind: SUBSTRUCTURE storeys: [1] } "
    "nodes { id: 3 kind: SUBSTRUCTURE storeys: [2] } nodes { id: 2 kind: ACTUATOR_EMULATOR } }";
const std::string kFractionCases =
    "cases { name: \"reference\" } cases { name: \"lag\" delay { shift { delay: 0.003 } } }";

INSTANTIATE_TEST_SUITE_P(
    Deployments, InProcessEqualsSimulate,
    testing::Values(
        Variant{"paper_reference", test::paper_frame_study(5, kTwoNodes), "reference"},
        Variant{"paper_shift", test::paper_frame_study(5, kTwoNodes), "lag_shift_14ms"},
        Variant{"paper_jitter", test::paper_frame_study(5, kTwoNodes), "jitter"},
        Variant{"paper_local_numerical", test::paper_frame_study(5, kLocalNumerical),
                "lag_shift_14ms"},
        Variant{"storey_split",
                test::two_storey_study(
                    4, kFractionCases, kSplit,
                    "substructuring { experimental_fraction: 0.5 model { linear {} } }"),
                "lag"},
        Variant{"bilinear_storey2", test::two_storey_study(4, kFractionCases, kTwoNodes), "lag"}),
    [](const auto& info) { return std::string(info.param.name); });

// A 14 ms shift put on what the actuator emulator receives (a node delay stage) instead of on the
// actuator (the case) reproduces the delayed case of core::simulate exactly.
TEST(InProcess, NodeReceiveDelayReproducesTheDelayedCase) {
  const std::string text = test::paper_frame_study(
      5,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR "
      "receive_delay { shift { delay: 0.014 } } } }");
  const study::PreparedStudy prepared = test::prepare(text);
  coordinator::CoordinatorOptions options;
  options.run_id = "node-delay";
  options.case_name = "reference";
  const auto outcome = coordinator::run_in_process(prepared, options);
  ASSERT_TRUE(outcome.ok) << outcome.status;
  const auto delayed = core::simulate(
      study::setup_for_case(prepared, study::find_case(prepared.config, "lag_shift_14ms")),
      prepared.motion);
  expect_identical(outcome.result, delayed);
}

TEST(InProcess, NodeSendDelayDelaysTheForce) {
  const std::string text = test::paper_frame_study(
      3,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE send_delay { shift { delay: 0.014 } } } "
      "nodes { id: 2 kind: ACTUATOR_EMULATOR } }");
  coordinator::CoordinatorOptions options;
  options.run_id = "send-delay";
  options.case_name = "reference";
  const auto outcome = coordinator::run_in_process(test::prepare(text), options);
  ASSERT_TRUE(outcome.ok) << outcome.status;
  const auto undelayed = test::reference_result(text, "reference");
  // Same length, different response: the numerical storey's force now arrives 14 ms late.
  ASSERT_EQ(outcome.result.steps(), undelayed.steps());
  EXPECT_GT((outcome.result.displacement - undelayed.displacement).cwiseAbs().maxCoeff(), 1e-5);
}

// The emulator node's compensation block (deployment) acts as the case's block does (study).
TEST(InProcess, CompensationOnTheEmulatorNodeEqualsTheCasesBitForBit) {
  const std::string block = "compensation { polynomial { order: 2 lead: 0.014 } }";
  const std::string text = test::paper_frame_study(
      2, "cases { name: \"compensated\" delay { shift { delay: 0.014 } } " + block + " }\n" +
             "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: "
             "ACTUATOR_EMULATOR " +
             block + " } }");
  coordinator::CoordinatorOptions options;
  options.run_id = "node-compensation";
  options.case_name = "lag_shift_14ms";
  const auto outcome = coordinator::run_in_process(test::prepare(text), options);
  ASSERT_TRUE(outcome.ok) << outcome.status;
  const auto in_case = test::reference_result(text, "compensated");
  expect_identical(outcome.result, in_case);
  EXPECT_GT((in_case.displacement - test::reference_result(text, "lag_shift_14ms").displacement)
                .cwiseAbs()
                .maxCoeff(),
            1e-6);
}

// Compensation given twice (case and node), on a substructure node, or in a count that fits
// neither "one for all" nor "one per hosted actuator" is refused naming the node.
TEST(InProcess, MisplacedNodeCompensationIsRefusedNamingTheNode) {
  const std::string block = "compensation { polynomial { order: 2 lead: 0.014 } }";
  const auto refusal = [](const std::string& text, const std::string& case_name) -> std::string {
    coordinator::CoordinatorOptions options;
    options.run_id = "x";
    options.case_name = case_name;
    try {
      coordinator::run_in_process(test::prepare(text), options);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string twice =
      refusal(test::paper_frame_study(1, "cases { name: \"c\" " + block +
                                             " }\n deployment { nodes { id: 2 "
                                             "kind: ACTUATOR_EMULATOR " +
                                             block + " } }"),
              "c");
  EXPECT_NE(twice.find("nodes[id 2]"), std::string::npos) << twice;
  EXPECT_NE(twice.find("one place"), std::string::npos) << twice;
  const std::string substructure =
      refusal(test::paper_frame_study(1, "deployment { nodes { id: 1 kind: SUBSTRUCTURE " + block +
                                             " } nodes { id: 2 kind: ACTUATOR_EMULATOR } }"),
              "reference");
  EXPECT_NE(substructure.find("nodes[id 1]"), std::string::npos) << substructure;
  EXPECT_NE(substructure.find("ACTUATOR_EMULATOR"), std::string::npos) << substructure;
  const std::string count =
      refusal(test::paper_frame_study(1, "deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR " +
                                             block + " " + block + " } }"),
              "reference");
  EXPECT_NE(count.find("2 compensation blocks for 1 actuators"), std::string::npos) << count;
  const std::string bad = refusal(
      test::paper_frame_study(1,
                              "deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR compensation { "
                              "polynomial { order: 7 lead: 0.01 } } } }"),
      "reference");
  EXPECT_NE(bad.find("nodes[id 2] compensation[0]"), std::string::npos) << bad;
}

TEST(InProcess, ABadNodeDelayStageIsRefusedNamingTheNodeBeforeTheRun) {
  const std::string text = test::paper_frame_study(
      1,
      "deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR receive_delay { first_order { "
      "time_constant: -1 } } } }");
  coordinator::CoordinatorOptions options;
  options.run_id = "x";
  try {
    coordinator::run_in_process(test::prepare(text), options);
    ADD_FAILURE() << "a negative time constant was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("deployment.nodes[id 2].receive_delay"), std::string::npos)
        << e.what();
  }
}

TEST(InProcess, DeploymentThatDoesNotCoverTheExperimentalStoreyIsRefused) {
  const std::string text =
      test::paper_frame_study(1, "deployment { nodes { id: 1 kind: SUBSTRUCTURE } }");
  coordinator::CoordinatorOptions options;
  options.run_id = "x";
  EXPECT_THROW(
      {
        try {
          coordinator::run_in_process(test::prepare(text), options);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("experimental storey 1"), std::string::npos)
              << e.what();
          throw;
        }
      },
      std::invalid_argument);
}

TEST(InProcess, DisplacementLimitStopsTheRunAndKeepsStepsBeforeIt) {
  const std::string text =
      test::paper_frame_study(5, "deployment { limits { max_displacement: 0.002 } }");
  coordinator::CoordinatorOptions options;
  options.run_id = "limits";
  const auto outcome = coordinator::run_in_process(test::prepare(text), options);
  EXPECT_FALSE(outcome.ok);
  EXPECT_NE(outcome.status.find("safety limit"), std::string::npos) << outcome.status;
  ASSERT_GT(outcome.result.steps(), 10u);
  EXPECT_LE(outcome.result.displacement.cwiseAbs().maxCoeff(), 0.002);
}

}  // namespace
}  // namespace rths
