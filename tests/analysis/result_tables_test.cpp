// analysis/result_tables: a study's, a distributed study's and a sweep's tables have the CSV's
// variable names, SI units and NaN where a value is missing.
#include "analysis/result_tables.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "analysis/sweep_csv.h"
#include "analysis/sweep_grid.h"
#include "study/motion_key.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

using results::Table;

const std::string kMotion =
    std::string(RTHS_SOURCE_DIR) + "/data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";

std::vector<std::string> names(const Table& t) {
  std::vector<std::string> out;
  for (const auto& c : t.columns()) out.push_back(c.name);
  return out;
}

CaseOutcome make_case(const std::string& name, std::size_t steps, bool actuator) {
  CaseOutcome c;
  c.name = name;
  c.simulation.dt = 0.01;
  c.simulation.time.resize(steps);
  for (std::size_t k = 0; k < steps; ++k) {
    c.simulation.time[k] = 0.01 * static_cast<double>(k);
    c.response.push_back(0.001 * static_cast<double>(k));
  }
  c.simulation.displacement =
      Eigen::Map<const Eigen::VectorXd>(c.response.data(), static_cast<Eigen::Index>(steps));
  const auto n = static_cast<Eigen::Index>(actuator ? steps : 0);
  c.simulation.command = Eigen::MatrixXd::Constant(n, actuator ? 1 : 0, 0.5);
  c.simulation.realised = Eigen::MatrixXd::Constant(n, actuator ? 1 : 0, 0.25);
  c.simulation.measured_force = Eigen::MatrixXd::Constant(n, actuator ? 1 : 0, 100.0);
  return c;
}

TEST(ResultTables, StudyTableNamesEachCaseAndPadsAStoppedCaseWithNan) {
  StudyOutcome outcome;
  outcome.study_name = "frame";
  outcome.cases = {make_case("reference", 5, false), make_case("lag 14ms", 3, true)};
  const Table t = study_table(outcome);
  EXPECT_EQ(names(t),
            (std::vector<std::string>{"step", "time_s", "reference_u_floor1_m",
                                      "lag_14ms_u_floor1_m", "lag_14ms_command_act1_m",
                                      "lag_14ms_measured_act1_m", "lag_14ms_force_act1_N"}));
  EXPECT_EQ(t.rows(), 5u);
  EXPECT_DOUBLE_EQ(t.column("time_s").numbers[4], 0.04);
  EXPECT_DOUBLE_EQ(t.column("step").numbers[4], 4.0);
  EXPECT_DOUBLE_EQ(t.column("lag_14ms_u_floor1_m").numbers[2], 0.002);
  EXPECT_TRUE(std::isnan(t.column("lag_14ms_u_floor1_m").numbers[3]));
  EXPECT_TRUE(std::isnan(t.column("lag_14ms_force_act1_N").numbers[4]));
  EXPECT_EQ(t.column("lag_14ms_force_act1_N").unit, "N");
  EXPECT_EQ(t.attributes().at("reference_case"), "reference");
}

TEST(ResultTables, StudyTableCarriesTheStudyStepMotionAndVerdict) {
  StudyOutcome outcome;
  outcome.study_name = "frame";
  outcome.motion_name = "RSN175";
  outcome.motion_sha256 = std::string(64, 'a');
  outcome.motion_file_sha256 = std::string(64, 'b');
  outcome.cases = {make_case("reference", 5, false), make_case("lag 40ms", 5, true)};
  outcome.cases[1].status = "diverged";
  outcome.cases[1].expect_unstable = true;
  const Table expected_divergence = study_table(outcome);
  EXPECT_EQ(expected_divergence.attributes().at("study"), "frame");
  EXPECT_DOUBLE_EQ(expected_divergence.number_attributes().at("dt_s"), 0.01);
  EXPECT_EQ(expected_divergence.attributes().at("motion_name"), "RSN175");
  EXPECT_EQ(expected_divergence.attributes().at("motion_sha256"), std::string(64, 'a'));
  EXPECT_EQ(expected_divergence.attributes().at("motion_file_sha256"), std::string(64, 'b'));
  EXPECT_EQ(expected_divergence.attributes().at("status"), "lag 40ms: diverged");
  EXPECT_EQ(expected_divergence.number_attributes().at("ok"), 1.0) << "the divergence was meant";

  outcome.cases[1].expect_unstable = false;
  EXPECT_EQ(study_table(outcome).number_attributes().at("ok"), 0.0);
  outcome.cases[1].status = "completed";
  const Table completed = study_table(outcome);
  EXPECT_EQ(completed.attributes().at("status"), "completed");
  EXPECT_EQ(completed.number_attributes().at("ok"), 1.0);
}

TEST(ResultTables, DistributedTableIsTheStudyTablePlusLagPerLinkAtTheCarryingStep) {
  StudyOutcome outcome;
  outcome.study_name = "frame";
  outcome.cases = {make_case("lag 14ms", 4, true)};
  std::map<int, runtime::LinkSeries> links;
  runtime::LinkSeries& s = links[2];
  s.node_id = 2;
  s.time = {0.01, 0.03};  // answers carried by steps 1 and 3; step 2 reused an older one
  s.answered_step = {1, 3};
  s.round_trip = {0.0021, 0.0023};
  s.injected = {0.014, 0.014};
  const Table t = distributed_study_table(outcome, {links});
  std::vector<std::string> expected = names(study_table(outcome));
  expected.push_back("lag_14ms_node2_injected_lag_s");
  expected.push_back("lag_14ms_node2_round_trip_s");
  EXPECT_EQ(names(t), expected);
  const auto& rtt = t.column("lag_14ms_node2_round_trip_s").numbers;
  ASSERT_EQ(rtt.size(), 4u);
  EXPECT_TRUE(std::isnan(rtt[0]));
  EXPECT_DOUBLE_EQ(rtt[1], 0.0021);
  EXPECT_TRUE(std::isnan(rtt[2]));
  EXPECT_DOUBLE_EQ(rtt[3], 0.0023);
  EXPECT_EQ(t.column("lag_14ms_node2_injected_lag_s").unit, "s");
  EXPECT_THROW(distributed_study_table(outcome, {}), std::invalid_argument);
}

TEST(ResultTables, SweepTableHasTheSweepCsvsColumnsInOrder) {
  const config::Study study = core::parse_study(
      "name: \"s\" structure { sdof { period: 0.5 } damping { modal_zeta: 0.05 } }\n"
      "integrator { kind: EXPLICIT_NEWMARK dt: 0.005 }\n"
      "sweep { periods: [0.4, 0.8] delays: [0.01] motions { path: \"" +
          kMotion + "\" duration: 2 } }\n",
      "test");
  const SweepGrid grid(study, RTHS_SOURCE_DIR, "test");
  const auto rows = run_sweep(grid, {});
  const auto csv = std::filesystem::temp_directory_path() /
                   ("rths_tables_sweep_" + std::to_string(getpid()) + ".csv");
  write_sweep_csv(csv, grid, {}, rows);
  std::ifstream in(csv);
  std::string header;
  std::getline(in, header);
  std::filesystem::remove(csv);

  const Table t = sweep_table(to_table(grid, rows), grid.hash_hex(), grid.size());
  std::string joined;
  for (const auto& n : names(t)) joined += (joined.empty() ? "" : ",") + n;
  EXPECT_EQ(joined, header);
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_DOUBLE_EQ(t.column("period_s").numbers[1], 0.8);
  EXPECT_TRUE(t.column("motion").is_text);
  EXPECT_EQ(t.attributes().at("grid_hash"), grid.hash_hex());
}

}  // namespace
}  // namespace rths::analysis
