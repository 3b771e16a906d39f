// Compensated cases over Cyclone DDS: the actuator emulator builds its actuators, compensator
// included, from the same study case as the in-process run, so a lockstep run equals it bit for
// bit. Real processes on loopback, on the shared DDS domain, each test on topics of its own.
#include <gtest/gtest.h>

#include "core/compensation.h"
#include "runtime/node/lag.h"
#include "test_support.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

class DdsCompensation : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

// The identified MTS actuator (4.6 ms shift + 21.8 ms first order) on every actuator.
constexpr const char* kMtsActuator =
    "delay { shift { delay: 0.0046 } } delay { first_order { time_constant: 0.0218 } }";

TEST_F(DdsCompensation, AdaptiveAndModelBasedPerActuatorEqualInProcessBitForBit) {
  // Two storeys, half of each storey experimental: two actuators, one compensator each. ATS uses
  // the measured feedback, so this also checks that the emulator's feedback path is the in-process
  // one.
  const std::string cases =
      std::string(
          "cases { name: \"reference\" }\n"
          "cases { name: \"compensated\" ") +
      kMtsActuator +
      " compensation { adaptive_time_series { window: 0.2 initial_a1: 0.02 } }"
      " compensation { model_based { plant { shift { delay: 0.0046 } } plant { first_order { "
      "time_constant: 0.0218 } } lead_order: 2 rolloff_frequency: 40 } } }";
  const std::string text = test::two_storey_study(
      2, cases, "", "substructuring { experimental_fraction: 0.5 model { linear {} } }");
  const core::SimulationResult in_process = test::reference_result(text, "compensated");
  ASSERT_EQ(in_process.command.cols(), 2);
  // The compensators act: the realised drift differs from what the same actuator realises bare.
  const study::PreparedStudy prepared = test::prepare(text);
  core::HybridSetup bare =
      study::setup_for_case(prepared, study::find_case(prepared.config, "compensated"));
  for (auto& chain : bare.delays) chain.set_compensator(nullptr);
  const core::SimulationResult uncompensated = core::simulate(bare, prepared.motion);
  EXPECT_NE(uncompensated.realised(500, 0), in_process.realised(500, 0));
  EXPECT_NE(uncompensated.realised(500, 1), in_process.realised(500, 1));

  const auto run =
      test::launch("compensated_lockstep", text, "compensated", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_FALSE(run.record.truncated);
  test::expect_record_equals(run.record, in_process);
  for (int code : run.launch.node_exits) EXPECT_EQ(code, 0);
}

TEST_F(DdsCompensation, PolynomialOnThePaperFrameEqualsInProcessBitForBit) {
  const std::string text = test::paper_frame_study(
      2, std::string("cases { name: \"poly\" ") + kMtsActuator +
             " compensation { polynomial { order: 2 lead: 0.0264 spacing: 0.008 } } }");
  const auto run = test::launch("compensated_poly", text, "poly", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  test::expect_record_equals(run.record, test::reference_result(text, "poly"));
}

// The model-based inverse with its adaptive correction against an actuator 30 % slower than the
// model: the correction adapts from the emulator's measured feedback (window 0.2 s, so it fits
// within the run), and the lockstep record still equals the in-process one bit for bit.
TEST_F(DdsCompensation, AdaptedModelBasedOnThePaperFrameEqualsInProcessBitForBit) {
  const std::string text = test::paper_frame_study(
      2,
      "cases { name: \"adapted\" delay { shift { delay: 0.00598 } } "
      "delay { first_order { time_constant: 0.02834 } } compensation { model_based { "
      "plant { shift { delay: 0.0046 } } plant { first_order { time_constant: 0.0218 } } "
      "lead_order: 2 rolloff_frequency: 50 adaptive_correction { window: 0.2 } } } }\n"
      "cases { name: \"fixed\" delay { shift { delay: 0.00598 } } "
      "delay { first_order { time_constant: 0.02834 } } compensation { model_based { "
      "plant { shift { delay: 0.0046 } } plant { first_order { time_constant: 0.0218 } } "
      "lead_order: 2 rolloff_frequency: 50 } } }");
  const core::SimulationResult in_process = test::reference_result(text, "adapted");
  // The correction acts once its window has filled: it departs from the fixed feedforward.
  const core::SimulationResult fixed = test::reference_result(text, "fixed");
  EXPECT_EQ(fixed.realised(100, 0), in_process.realised(100, 0));
  EXPECT_NE(fixed.realised(1500, 0), in_process.realised(1500, 0));
  const auto run =
      test::launch("compensated_adapted", text, "adapted", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_FALSE(run.record.truncated);
  test::expect_record_equals(run.record, in_process);
}

// The compensation given on the emulator nodes of the deployment (one node per actuator, each its
// own block), not in the case: the lockstep record equals the in-process run of a case that gives
// the same blocks per actuator, bit for bit.
TEST_F(DdsCompensation, CompensationOnTheEmulatorNodesEqualsTheCasesBitForBit) {
  constexpr const char* kAts = "adaptive_time_series { window: 0.2 initial_a1: 0.02 }";
  constexpr const char* kModelBased =
      "model_based { plant { shift { delay: 0.0046 } } plant { first_order { time_constant: "
      "0.0218 } } lead_order: 2 rolloff_frequency: 40 }";
  const std::string cases = std::string("cases { name: \"mts\" ") + kMtsActuator + " }\n" +
                            "cases { name: \"in_case\" " + kMtsActuator + " compensation { " +
                            kModelBased + " } compensation { " + kAts + " } }";
  const std::string deployment =
      std::string("deployment { nodes { id: 1 kind: SUBSTRUCTURE } ") +
      "nodes { id: 2 kind: ACTUATOR_EMULATOR storeys: [1] compensation { " + kModelBased + " } } " +
      "nodes { id: 3 kind: ACTUATOR_EMULATOR storeys: [2] compensation { " + kAts + " } } }";
  const std::string text = test::two_storey_study(
      2, cases, deployment, "substructuring { experimental_fraction: 0.5 model { linear {} } }");
  const core::SimulationResult in_case = test::reference_result(text, "in_case");
  const core::SimulationResult bare = test::reference_result(text, "mts");
  EXPECT_NE(bare.realised(500, 0), in_case.realised(500, 0));  // the blocks act
  EXPECT_NE(bare.realised(500, 1), in_case.realised(500, 1));
  const auto run =
      test::launch("compensated_on_nodes", text, "mts", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_FALSE(run.record.truncated);
  test::expect_record_equals(run.record, in_case);
}

}  // namespace
}  // namespace rths
