// Experimental elements between two DOFs (a storey's specimen, OpenFresco's twoNodeLink) on the
// lab's 3-DOF frame: without lag the hybrid frame is the whole frame; in lockstep over DDS it is
// the in-process run bit for bit, with one specimen and with two specimens on two actuator nodes.
// The shared DDS domain, each test on topics of its own.
#include <gtest/gtest.h>

#include "runtime/node/lag.h"
#include "test_support.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

// The lab's frame (SI): floor masses 1000, 1000, 800 kg; storeys 2e6, 2e6, 1.5e6 N/m.
constexpr const char* kFrame =
    "structure { matrices {"
    " mass { rows: 3 values: [1000, 0, 0, 0, 1000, 0, 0, 0, 800] }"
    " stiffness { rows: 3 values: [4e6, -2e6, 0, -2e6, 3.5e6, -1.5e6, 0, -1.5e6, 1.5e6] }"
    " } damping { rayleigh { zeta: 0.03 } } }\n"
    "integrator { kind: EXPLICIT_NEWMARK dt: 0.002 }\n";

std::string frame_study(const std::string& substructuring, const std::string& deployment = "",
                        double duration = 4) {
  return std::string("name: \"frame3_elements\"\n") + kFrame + "motion { path: \"" +
         test::motion_path() + "\" duration: " + std::to_string(duration) + " }\n" +
         substructuring + "cases { name: \"reference\" }\n" +
         "cases { name: \"lag\" delay { shift { delay: 0.004 } } }\n" + deployment;
}

// The whole second storey (2e6 N/m) is the specimen, between floors 1 and 2.
constexpr const char* kStoreyTwo =
    "substructuring { experimental_dofs { dof: 2 from_dof: 1 stiffness: 2e6 } }\n";
// Half of storeys 2 and 3, each its own specimen and actuator.
constexpr const char* kStoreysTwoAndThree =
    "substructuring { experimental_dofs { dof: 2 from_dof: 1 stiffness: 1e6 }"
    " experimental_dofs { dof: 3 from_dof: 2 stiffness: 0.75e6 } }\n";

class DdsExperimentalElement : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_F(DdsExperimentalElement, WithoutLagTheHybridFrameIsTheWholeFrame) {
  const core::SimulationResult whole = test::reference_result(frame_study(""), "reference");
  const core::SimulationResult hybrid =
      test::reference_result(frame_study(kStoreyTwo), "reference");
  ASSERT_EQ(hybrid.steps(), whole.steps());
  ASSERT_EQ(hybrid.measured_force.cols(), 1);
  const double scale = whole.displacement.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 1e-4);
  EXPECT_LE((hybrid.displacement - whole.displacement).cwiseAbs().maxCoeff(), 1e-12 * scale);
  // The actuator imposes the storey's drift and measures its shear k (u2 - u1).
  const Eigen::VectorXd drift = whole.displacement.col(1) - whole.displacement.col(0);
  EXPECT_LE((hybrid.command.col(0) - drift).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_LE((hybrid.measured_force.col(0) - 2e6 * drift).cwiseAbs().maxCoeff(),
            1e-12 * 2e6 * scale);
}

TEST_F(DdsExperimentalElement, ABraceAtAnAngleCarriesItsShareOfTheStorey) {
  // A brace at 60 degrees of axial stiffness k_b adds k_b cos^2 = k_b / 4 to the storey: a
  // 4e6 N/m brace is the whole 1e6 N/m of half the second storey.
  const std::string brace =
      "substructuring { experimental_dofs { dof: 2 from_dof: 1 angle_degrees: 60 stiffness: 4e6 "
      "} }\n";
  const core::SimulationResult whole = test::reference_result(frame_study(""), "reference");
  const core::SimulationResult hybrid = test::reference_result(frame_study(brace), "reference");
  const double scale = whole.displacement.cwiseAbs().maxCoeff();
  EXPECT_LE((hybrid.displacement - whole.displacement).cwiseAbs().maxCoeff(), 1e-12 * scale);
  const Eigen::VectorXd axial = 0.5 * (whole.displacement.col(1) - whole.displacement.col(0));
  EXPECT_LE((hybrid.command.col(0) - axial).cwiseAbs().maxCoeff(), 1e-12 * scale);
}

TEST_F(DdsExperimentalElement, StoreySpecimenInLockstepEqualsTheInProcessRunBitForBit) {
  const std::string text = frame_study(kStoreyTwo);
  const auto run = test::launch("element_lockstep", text, "lag", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_NE(run.record.footer(), nullptr);
  EXPECT_TRUE(run.record.footer()->ok());
  test::expect_record_equals(run.record, test::reference_result(text, "lag"));
  for (int code : run.launch.node_exits) EXPECT_EQ(code, 0);
}

TEST_F(DdsExperimentalElement, TwoSpecimensOnTwoActuatorNodesInLockstepEqualTheInProcessRun) {
  // Channels: DOFs 1-3, then element 1 (channel 4) and element 2 (channel 5).
  const std::string text = frame_study(kStoreysTwoAndThree,
                                       "deployment { nodes { id: 1 kind: SUBSTRUCTURE }"
                                       " nodes { id: 2 kind: ACTUATOR_EMULATOR storeys: 4 }"
                                       " nodes { id: 3 kind: ACTUATOR_EMULATOR storeys: 5 } }\n");
  const auto run = test::launch("element_two_nodes", text, "lag", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_EQ(run.launch.node_exits.size(), 3u);
  const core::SimulationResult reference = test::reference_result(text, "lag");
  ASSERT_EQ(reference.measured_force.cols(), 2);
  EXPECT_GT(reference.measured_force.col(1).cwiseAbs().maxCoeff(), 100.0);
  test::expect_record_equals(run.record, reference);
  for (int code : run.launch.node_exits) EXPECT_EQ(code, 0);
}

}  // namespace
}  // namespace rths
