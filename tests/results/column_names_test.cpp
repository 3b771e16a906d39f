#include "results/column_names.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "results/table.h"

namespace rths::results {
namespace {

core::SimulationResult three_floors_two_actuators(std::size_t steps) {
  core::SimulationResult r;
  r.dt = 0.001;
  r.time.resize(steps);
  const auto n = static_cast<Eigen::Index>(steps);
  r.displacement = core::Mat::Constant(n, 3, 0.25);
  r.velocity = r.acceleration = core::Mat::Zero(n, 3);
  r.command = core::Mat::Constant(n, 2, 0.5);
  r.realised = core::Mat::Constant(n, 2, 0.125);
  r.measured_force = core::Mat::Constant(n, 2, 1000.0);
  return r;
}

TEST(ResultsCsv, EveryFloorAndEveryActuatorWithUnitsInTheNames) {
  const auto r = three_floors_two_actuators(4);
  const auto names = result_column_names("lag 14ms", r);
  const std::vector<std::string> expected = {
      "lag_14ms_u_floor1_m",     "lag_14ms_u_floor2_m",      "lag_14ms_u_floor3_m",
      "lag_14ms_command_act1_m", "lag_14ms_measured_act1_m", "lag_14ms_force_act1_N",
      "lag_14ms_command_act2_m", "lag_14ms_measured_act2_m", "lag_14ms_force_act2_N"};
  EXPECT_EQ(names, expected);
}

TEST(ResultsCsv, ARecordsVelocityAndAccelerationAreNamedAsItsDisplacement) {
  EXPECT_EQ(displacement_column(2), "u_floor2_m");
  EXPECT_EQ(velocity_column(2), "v_floor2_m_per_s");
  EXPECT_EQ(acceleration_column(2), "a_floor2_m_per_s2");
  EXPECT_EQ(measured_column(12), "measured_act12_m");
}

TEST(ResultsCsv, ADriftNamesBothEndsAndTheGroundAndEndsInItsUnit) {
  EXPECT_EQ(drift_column(5, 4), "drift_floor5_floor4_m");
  EXPECT_EQ(drift_column(1, 0), "drift_floor1_ground_m");
  EXPECT_TRUE(is_identifier(drift_column(1000, 999)));
  EXPECT_EQ(std::string(kBaseShearColumn), "base_shear_N");
}

}  // namespace
}  // namespace rths::results
