// A structure given by its matrices (the 20-DOF frame of configs/matrix_frame20.textproto, Matrix
// Market files) in the three ways a study runs: in process, in lockstep over DDS (bit for bit
// equal) and in real time. The shared DDS domain, each test on topics of its own.
#include <gtest/gtest.h>

#include "runtime/node/lag.h"
#include "test_support.h"
#include "tests/support/dds_scope.h"
#include "tests/support/real_time_run.h"

namespace rths {
namespace {

std::string frame20_study(double duration, const std::string& deployment) {
  const std::string matrices = std::string(RTHS_SOURCE_DIR) + "/configs/matrices/";
  return "name: \"frame20\"\n"
         "structure { matrices { mass { file: \"" +
         matrices +
         "frame20_mass.mtx\" }"
         " stiffness { file: \"" +
         matrices +
         "frame20_stiffness.mtx\" } } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \"" +
         test::motion_path() + "\" duration: " + std::to_string(duration) +
         " }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.002 }\n"
         "substructuring { experimental_dofs { dof: 1 mass: 20 stiffness: 2.0e6 zeta: 0.02 } }\n"
         "cases { name: \"reference\" }\n"
         "cases { name: \"lag\" delay { shift { delay: 0.01 } } }\n" +
         deployment;
}

class DdsMatrixStructure : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

TEST_F(DdsMatrixStructure, InProcessRunHasEveryDofAndTheSpecimensForce) {
  const core::SimulationResult r = test::reference_result(frame20_study(3, ""), "lag");
  EXPECT_EQ(r.displacement.cols(), 20);
  EXPECT_EQ(r.measured_force.cols(), 1);
  EXPECT_FALSE(r.diverged);
  EXPECT_GT(r.displacement.col(19).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_GT(r.measured_force.cwiseAbs().maxCoeff(), 100.0);
}

TEST_F(DdsMatrixStructure, LockstepEqualsTheInProcessRunBitForBit) {
  const std::string text = frame20_study(3, "");
  const auto run = test::launch("matrix_lockstep", text, "lag", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_NE(run.record.footer(), nullptr);
  EXPECT_TRUE(run.record.footer()->ok());
  test::expect_record_equals(run.record, test::reference_result(text, "lag"));
  for (int code : run.launch.node_exits) EXPECT_EQ(code, 0);
}

TEST_F(DdsMatrixStructure, NumericalMatrixOnTheCoordinatorEqualsInProcessToo) {
  const std::string text =
      frame20_study(2, "deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR } }");
  const auto run = test::launch("matrix_local", text, "lag", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  test::expect_record_equals(run.record, test::reference_result(text, "lag"));
}

TEST_F(DdsMatrixStructure, RealTimeRunIsPacedAndCompletes) {
  const std::string text =
      frame20_study(1.0,
                    "deployment { clock: REAL_TIME max_overrun_fraction: -1 max_missed_answers: 30 "
                    "command_watchdog_periods: 30 }");
  const auto witnessed =
      test::launch_witnessed("matrix_real_time", text, "reference", test::scope_dds_to_this_test());
  RTHS_ASSERT_REAL_TIME_RUN_COMPLETED(witnessed);
  const auto& run = witnessed.run;
  const auto* footer = run.record.footer();
  ASSERT_NE(footer, nullptr);
  EXPECT_TRUE(footer->ok());
  EXPECT_EQ(run.record.steps().size(), 500u);
  EXPECT_GE(footer->wall_seconds(), 0.99);  // 500 steps of 2 ms cannot finish sooner
  EXPECT_EQ(run.record.header()->clock(), "real_time");
  EXPECT_EQ(run.record.steps().back()->displacement_size(), 20);
}

TEST_F(DdsMatrixStructure, ASubstructureNodeMustHostEveryCoupledDof) {
  const std::string text =
      frame20_study(1.0,
                    "deployment { nodes { id: 1 kind: SUBSTRUCTURE storeys: [1, 2] } "
                    "nodes { id: 3 kind: SUBSTRUCTURE storeys: [3, 4, 5, 6, 7, 8, 9, 10, 11, 12, "
                    "13, 14, 15, 16, 17, 18, 19, 20] } "
                    "nodes { id: 2 kind: ACTUATOR_EMULATOR } }");
  const study::PreparedStudy prepared = test::prepare(text);
  try {
    runtime::make_plan(prepared.base, prepared.config.deployment());
    FAIL() << "a split of coupled DOFs was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "deployment.nodes[id 1]: the numerical stiffness matrix couples"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rths
