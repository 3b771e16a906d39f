#include "analysis/results_csv.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace rths::analysis {
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
      "lag_14ms.u_floor1_m", "lag_14ms.u_floor2_m", "lag_14ms.u_floor3_m",
      "lag_14ms.command_act1_m", "lag_14ms.measured_act1_m", "lag_14ms.force_act1_N",
      "lag_14ms.command_act2_m", "lag_14ms.measured_act2_m", "lag_14ms.force_act2_N"};
  EXPECT_EQ(names, expected);
}

TEST(ResultsCsv, StepAndTimeFirstAndEmptyCellsAfterAnEarlyStop) {
  const auto full = three_floors_two_actuators(4);
  const auto stopped = three_floors_two_actuators(2);
  const auto path = std::filesystem::temp_directory_path() / ("rths_results_" + std::to_string(getpid()) + ".csv");
  write_results_csv(path, {{"ref", &full}, {"late", &stopped}});
  std::ifstream in(path);
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("step,time_s,ref.u_floor1_m,", 0), 0u) << header;
  std::size_t rows = 0;
  std::string last;
  while (std::getline(in, line)) {
    ++rows;
    last = line;
  }
  EXPECT_EQ(rows, 4u);
  EXPECT_EQ(last.rfind("3,0.003,0.25,", 0), 0u) << last;
  // `late` stopped after 2 steps: its 3 floor and 6 actuator cells are empty.
  EXPECT_EQ(last.substr(last.size() - 13), "1000,,,,,,,,,") << last;
  std::filesystem::remove(path);
  EXPECT_THROW(write_results_csv(path, {}), std::invalid_argument);
}

}  // namespace
}  // namespace rths::analysis
