// analysis/result_tables: a study's, a distributed study's and a sweep's tables have the CSV's
// variable names, SI units and NaN where a value is missing.
#include "analysis/tables/result_tables.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "analysis/sweep/sweep_csv.h"
#include "analysis/sweep/sweep_grid.h"
#include "core/metrics.h"
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

// A shear building of `floors` floors of 1000 kg and 1e6 N/m, storey 1 experimental, two cases,
// 0.5 s of the Imperial Valley record at its 5 ms step, with the given recorders blocks.
study::PreparedStudy chain_study(int floors, const std::string& recorders) {
  std::string masses, stiffnesses;
  for (int i = 0; i < floors; ++i) {
    masses += (i ? ", " : "") + std::string("1000");
    stiffnesses += (i ? ", " : "") + std::string("1e6");
  }
  return study::prepare_study(
      study::parse_study("name: \"chain\" structure { shear_building { storey_mass: [" + masses +
                             "] storey_stiffness: [" + stiffnesses +
                             "] } damping { modal_zeta: 0.05 } }\n"
                             "motion { path: \"" +
                             kMotion +
                             "\" duration: 0.5 }\n"
                             "substructuring { experimental_storeys: 1 }\n"
                             "cases { name: \"reference\" }\n"
                             "cases { name: \"lag\" delay { shift { delay: 0.01 } } }\n" +
                             recorders,
                         "test"),
      RTHS_SOURCE_DIR);
}

// Column `dof` (0-based) of a full run's displacement.
std::vector<double> full_column(const core::SimulationResult& r, int dof) {
  return std::vector<double>(r.displacement.col(dof).data(),
                             r.displacement.col(dof).data() + r.displacement.rows());
}

TEST(ResultTables, ALargeModelsTableHoldsTheDefaultRecordersColumnsAsAFullRunHasThem) {
  const study::PreparedStudy prepared = chain_study(250, "");
  const StudyOutcome outcome = run_study(prepared);
  ASSERT_EQ(outcome.cases.front().simulation.displacement.cols(), 5);  // not 250
  const Table t = study_table(outcome);
  EXPECT_EQ(
      names(t),
      (std::vector<std::string>{
          "step", "time_s", "reference_u_floor1_m", "reference_u_floor62_m",
          "reference_u_floor125_m", "reference_u_floor187_m", "reference_u_floor250_m",
          "reference_command_act1_m", "reference_measured_act1_m", "reference_force_act1_N",
          "lag_u_floor1_m", "lag_u_floor62_m", "lag_u_floor125_m", "lag_u_floor187_m",
          "lag_u_floor250_m", "lag_command_act1_m", "lag_measured_act1_m", "lag_force_act1_N"}));
  const core::SimulationResult full = core::simulate(prepared.base, prepared.motion);
  ASSERT_EQ(t.rows(), full.steps());
  EXPECT_EQ(t.column("reference_u_floor125_m").numbers, full_column(full, 124));
  EXPECT_EQ(t.column("reference_u_floor250_m").numbers, full_column(full, 249));
  EXPECT_GT(core::peak_abs(t.column("reference_u_floor250_m").numbers), 1e-4);  // m: it moved
  const TableShape shape =
      study_table_shape(prepared.recorders, prepared.motion.acceleration.size(), 2, 1);
  EXPECT_EQ(shape.rows, t.rows());
  EXPECT_EQ(shape.columns, t.columns().size());
}

TEST(ResultTables, DriftsBaseShearAndEveryKthStepAreWhatTheRecordersAskFor) {
  const study::PreparedStudy prepared =
      chain_study(3,
                  "recorders { drifts { dof: 3 from_dof: 2 } every: 2 }\n"
                  "recorders { base_shear: true dofs: 1 quantities: VELOCITY every: 3 }\n");
  const StudyOutcome outcome = run_study(prepared);
  const Table t = study_table(outcome);
  EXPECT_EQ(names(t),
            (std::vector<std::string>{"step", "time_s", "reference_drift_floor3_floor2_m",
                                      "reference_v_floor1_m_per_s", "reference_base_shear_N",
                                      "lag_drift_floor3_floor2_m", "lag_v_floor1_m_per_s",
                                      "lag_base_shear_N"}));
  const core::SimulationResult full = core::simulate(prepared.base, prepared.motion);
  const std::vector<double>& step = t.column("step").numbers;
  const std::vector<double>& drift = t.column("reference_drift_floor3_floor2_m").numbers;
  const std::vector<double>& shear = t.column("reference_base_shear_N").numbers;
  ASSERT_GE(step.size(), 6u);
  EXPECT_EQ(std::vector<double>(step.begin(), step.begin() + 6),
            (std::vector<double>{0, 2, 3, 4, 6, 8}));
  double largest_shear = 0.0;
  for (std::size_t r = 0; r < step.size(); ++r) {
    const auto k = static_cast<Eigen::Index>(step[r]);
    if (k % 2 == 0)
      EXPECT_EQ(drift[r], full.displacement(k, 2) - full.displacement(k, 1)) << "step " << k;
    else
      EXPECT_TRUE(std::isnan(drift[r])) << "step " << k;
    EXPECT_EQ(std::isnan(shear[r]), k % 3 != 0) << "step " << k;
    if (k % 3 == 0) {
      const double inertial =
          (prepared.base.model.mass *
           (full.acceleration.row(k).transpose() +
            core::Vec::Ones(3) * prepared.motion.acceleration[static_cast<std::size_t>(k)]))
              .sum();
      EXPECT_NEAR(shear[r], inertial, 1e-9 * std::abs(inertial) + 1e-9) << "step " << k;
      largest_shear = std::max(largest_shear, std::abs(shear[r]));
    }
  }
  EXPECT_GT(largest_shear, 10.0);  // N: the check compared forces, not zeros
}

TEST(ResultTables, SweepTableHasTheSweepCsvsColumnsInOrder) {
  const config::Study study = study::parse_study(
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
