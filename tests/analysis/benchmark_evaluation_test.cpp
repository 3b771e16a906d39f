// The RTHS benchmark's case 1 (configs/benchmark/case_1.textproto: El Centro at 40 %, nominal
// plant, the sample controller, seeded sensor noise) against its published Table 3 values.
#include "analysis/benchmark/benchmark_evaluation.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "study/motion_key.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

std::filesystem::path benchmark_config(const std::string& file) {
  return std::filesystem::path(RTHS_SOURCE_DIR) / "configs" / "benchmark" / file;
}

std::optional<BenchmarkEvaluation> evaluate(const config::Study& study,
                                            const std::filesystem::path& config) {
  const study::PreparedStudy prepared = study::prepare_study(study, config.parent_path());
  return evaluate_benchmark(prepared, run_study(prepared, {}));
}

// The published values of a case as shipped (sample controller, El Centro at 40 %, the
// benchmark's model integrated as it integrates it: EXACT_ZOH): J1 within 0.1 ms, J2-J9 within
// 2.5 % (J5, the peak of a noisy error, within 5 %). The published numbers are one draw of
// MATLAB's sensor noise, which no other generator repeats; J3 and J5 are peaks of the noisy
// x_m - x_t and x_m - d_ref and move by 1-2 % from one noise draw to another (case 2's J3 runs
// 11.0-11.5 over seeds), so they are compared as the mean of the shipped draw and four more
// seeds; the other criteria move by under 0.3 % and are compared draw by draw.
class TableThree : public ::testing::TestWithParam<int> {};

TEST_P(TableThree, CaseMeetsThePublishedCriteria) {
  const std::filesystem::path config =
      benchmark_config("case_" + std::to_string(GetParam()) + ".textproto");
  config::Study study = study::load_study(config);
  ASSERT_EQ(study.integrator().kind(), config::Integrator::EXACT_ZOH);
  ASSERT_EQ(study.cases(1).name(), "sample_controller");
  for (int seed = 1; seed <= 4; ++seed) {
    config::Case draw = study.cases(1);
    draw.set_name("sample_controller_seed_" + std::to_string(seed));
    draw.mutable_delay(0)->mutable_tracking_loop()->set_seed(static_cast<std::uint64_t>(seed));
    *study.add_cases() = draw;
  }
  const std::optional<BenchmarkEvaluation> evaluation = evaluate(study, config);
  ASSERT_TRUE(evaluation.has_value());
  ASSERT_EQ(evaluation->cases.size(), 5u);
  ASSERT_EQ(evaluation->published.size(), 9u);
  EXPECT_TRUE(evaluation->published_motion_matches);
  EXPECT_TRUE(evaluation->compared_with_published(evaluation->cases[0]));
  const auto published = [&](int j) { return evaluation->published[std::size_t(j - 1)]; };
  std::array<double, 9> mean{};
  for (const BenchmarkCaseCriteria& draw : evaluation->cases) {
    EXPECT_NEAR(draw.criteria.J(1) * 1e3, published(1), 0.1) << draw.name << " J1 (ms)";
    for (int j = 2; j <= 9; ++j) {
      mean[std::size_t(j - 1)] += draw.criteria.J(j) / 5.0;
      if (j == 3 || j == 5) continue;
      EXPECT_NEAR(draw.criteria.J(j), published(j), 0.025 * published(j)) << draw.name << " J" << j;
    }
  }
  EXPECT_NEAR(mean[2], published(3), 0.025 * published(3)) << "J3, mean of 5 noise draws";
  EXPECT_NEAR(mean[4], published(5), 0.05 * published(5)) << "J5, mean of 5 noise draws";
  std::cout << benchmark_table(*evaluation);
}

INSTANTIATE_TEST_SUITE_P(Cases, TableThree, ::testing::Values(1, 2, 3, 4));

// A study that asks for explicit Newmark still gets it: case 1 lands 3-5 % under Table 3 in J4-J9,
// the half sample of lag less that taking the force in the step's equilibrium gives.
TEST(BenchmarkEvaluation, ExplicitNewmarkRunsTheCaseWithLessLag) {
  const std::filesystem::path config = benchmark_config("case_1.textproto");
  config::Study study = study::load_study(config);
  const std::optional<BenchmarkEvaluation> exact = evaluate(study, config);
  study.mutable_integrator()->set_kind(config::Integrator::EXPLICIT_NEWMARK);
  const std::optional<BenchmarkEvaluation> newmark = evaluate(study, config);
  ASSERT_TRUE(exact && newmark);
  for (int j = 4; j <= 9; ++j) {
    const double published = newmark->published[std::size_t(j - 1)];
    EXPECT_LT(newmark->cases[0].criteria.J(j), exact->cases[0].criteria.J(j)) << "J" << j;
    EXPECT_NEAR(newmark->cases[0].criteria.J(j), published, 0.05 * published) << "J" << j;
  }
}

// Every criterion named, with its unit and definition, in the JSON.
TEST(BenchmarkEvaluation, CaseOneJsonNamesEveryCriterion) {
  const std::filesystem::path config = benchmark_config("case_1.textproto");
  const std::optional<BenchmarkEvaluation> evaluation = evaluate(study::load_study(config), config);
  ASSERT_TRUE(evaluation.has_value());
  const core::BenchmarkCriteria& measured = evaluation->cases[0].criteria;
  const nlohmann::json json = benchmark_json(*evaluation);
  const nlohmann::json& j5 = json["cases"][0]["criteria"][4];
  EXPECT_EQ(j5["name"], "J5");
  EXPECT_EQ(j5["unit"], "%");
  EXPECT_DOUBLE_EQ(j5["value"].get<double>(), measured.J(5));
  EXPECT_NE(j5["definition"].get<std::string>().find("max|x_m - d_ref|"), std::string::npos);
  EXPECT_EQ(json["cases"][0]["criteria"][0]["unit"], "ms");
  EXPECT_DOUBLE_EQ(json["cases"][0]["criteria"][0]["value"].get<double>(), measured.J(1) * 1e3);
  EXPECT_EQ(json["published"]["criteria"][3]["value"], 36.1);
  EXPECT_NEAR(json["cases"][0]["vs_published"][4]["value"].get<double>(),
              100.0 * (measured.J(5) - 19.0) / 19.0, 1e-9);
  EXPECT_FALSE(json.contains("units"));
}

// The same model on the benchmark's other motions, Kobe and Morgan Hill at 40 %
// (configs/benchmark/case_1_kobe, case_1_morgan_hill): it runs the whole record, stays stable,
// and says Table 3 has no value for it.
TEST(BenchmarkEvaluation, KobeAndMorganHillRunWithNoPublishedValue) {
  for (const std::string motion : {"kobe", "morgan_hill"}) {
    const std::filesystem::path config = benchmark_config("case_1_" + motion + ".textproto");
    const config::Study study = study::load_study(config);
    EXPECT_EQ(study.integrator().kind(), config::Integrator::EXACT_ZOH);
    const study::PreparedStudy prepared = study::prepare_study(study, config.parent_path());
    const StudyOutcome outcome = run_study(prepared, {});
    for (const CaseOutcome& c : outcome.cases) EXPECT_EQ(c.status, "completed") << c.name;
    const std::optional<BenchmarkEvaluation> evaluation = evaluate_benchmark(prepared, outcome);
    ASSERT_TRUE(evaluation.has_value());
    EXPECT_FALSE(evaluation->compared_with_published(evaluation->cases.at(0)));
    const double j1_ms = evaluation->cases[0].criteria.J(1) * 1e3;
    EXPECT_NEAR(j1_ms, 4.6, 0.1) << motion << ": the tracking loop's delay is the motion's too";
    const std::string table = benchmark_table(*evaluation);
    EXPECT_NE(table.find("no published value: this run's motion (" + motion + ".txt)"),
              std::string::npos)
        << table;
  }
}

// The table's columns line up: the published row, each case and the header have their cells
// under the same header, one unit per column.
TEST(BenchmarkEvaluation, TheTableIsAlignedWithOneUnitPerColumn) {
  BenchmarkEvaluation e;
  e.published = {4.6, 10.4, 11.5, 36.1, 19.0, 32.3, 32.4, 14.8, 14.8};
  e.published_case = "sample_controller";
  e.published_source = "Silva et al. 2020, Table 3, case 1, El Centro";
  e.published_motion_matches = true;
  e.dt = 1.0 / 4096;
  e.j1_search = 49 * e.dt;
  core::BenchmarkCriteria c;
  c.j = {0.0047, 9.9, 11.0, 34.6, 18.1, 31.0, 31.2, 14.2, 14.3};
  e.cases = {{"sample_controller", c}, {"a_compensated_case_with_a_long_name", c}};
  const std::string table = benchmark_table(e);
  std::istringstream lines(table);
  std::vector<std::string> block;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("case ", 0) == 0 || line.rfind("published (", 0) == 0 ||
        line.rfind("sample_controller ", 0) == 0 || line.rfind("a_compensated", 0) == 0)
      block.push_back(line);
  }
  ASSERT_GE(block.size(), 4u) << table;
  // Right-aligned numbers: every line of the first table ends at its header's end, and J1's
  // column ends at the same place in each.
  const std::size_t j1_end = block[0].find("J1 (ms)") + std::string("J1 (ms)").size();
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(block[i].size(), block[0].size()) << table;
    EXPECT_NE(block[i][j1_end - 1], ' ') << block[i];
    EXPECT_TRUE(j1_end == block[i].size() || block[i][j1_end] == ' ') << block[i];
  }
  EXPECT_NE(table.find("J1 diff (ms)"), std::string::npos) << table;
  EXPECT_NE(table.find("J5 rel (%)"), std::string::npos) << table;
  EXPECT_NE(table.find("no published value for a_compensated_case_with_a_long_name"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("J6 (%)   100 std(u_i - u_ref,i)"), std::string::npos) << table;
  const nlohmann::json json = benchmark_json(e);
  EXPECT_FALSE(json["cases"][0]["vs_published"].is_null());
  EXPECT_TRUE(json["cases"][1]["vs_published"].is_null());
}

// The published values belong to El Centro at 40 %: a run on another motion has none, and says so.
TEST(BenchmarkEvaluation, AnotherMotionHasNoPublishedValue) {
  const std::filesystem::path config =
      std::filesystem::path(RTHS_SOURCE_DIR) / "configs/benchmark/case_1.textproto";
  config::Study study = study::load_study(config);
  study.mutable_motion()->set_path("kobe.txt");
  study.mutable_motion()->set_duration(4.0);
  const study::PreparedStudy prepared = study::prepare_study(study, config.parent_path());
  const std::optional<BenchmarkEvaluation> evaluation =
      evaluate_benchmark(prepared, run_study(prepared, {}));
  ASSERT_TRUE(evaluation.has_value());
  EXPECT_FALSE(evaluation->published_motion_matches);
  EXPECT_FALSE(evaluation->compared_with_published(evaluation->cases.at(0)));
  const std::string table = benchmark_table(*evaluation);
  EXPECT_EQ(table.find("rel (%)"), std::string::npos) << table;
  EXPECT_NE(table.find("no published value: this run's motion (kobe.txt) is not the one"),
            std::string::npos)
      << table;
  const nlohmann::json json = benchmark_json(*evaluation);
  EXPECT_TRUE(json["cases"][0]["vs_published"].is_null());
  EXPECT_FALSE(json["published"]["motion_matches"].get<bool>());
  // The same motion cut short is not the published one either.
  study.mutable_motion()->set_path("el_centro.txt");
  const study::PreparedStudy cut = study::prepare_study(study, config.parent_path());
  EXPECT_FALSE(evaluate_benchmark(cut, run_study(cut, {}))->published_motion_matches);
}

// The published values are keyed by what was run, not by a path: the same structure said another
// way (its influence vector written out) keeps them; the structure changed (the ground load at
// 90 %) loses them, and no published row is printed, naming this run's keys.
TEST(BenchmarkEvaluation, ThePublishedValuesAreKeyedByContent) {
  const std::filesystem::path config =
      std::filesystem::path(RTHS_SOURCE_DIR) / "configs/benchmark/case_1.textproto";
  config::Study study = study::load_study(config);
  study.mutable_motion()->set_duration(2.0);
  const study::PreparedStudy cut = study::prepare_study(study, config.parent_path());
  const std::optional<BenchmarkEvaluation> as_cut = evaluate_benchmark(cut, run_study(cut, {}));
  ASSERT_TRUE(as_cut.has_value());
  EXPECT_FALSE(as_cut->published_motion_matches);
  study = study::load_study(config);
  const core::StructuralModel whole =
      study::make_structure(study.structure(), config.parent_path());
  EXPECT_EQ(structure_key(whole), study.benchmark().published_structure_sha256());
  EXPECT_EQ(study::motion_key(study::load_motion(study.motion(), config.parent_path())),
            study.benchmark().published_motion_sha256());
  auto* influence = study.mutable_structure()->mutable_matrices()->mutable_influence();
  influence->set_rows(whole.dofs());
  for (int i = 0; i < whole.dofs(); ++i) influence->add_values(1.0);
  EXPECT_EQ(structure_key(study::make_structure(study.structure(), config.parent_path())),
            structure_key(whole));
  for (double& v : *influence->mutable_values()) v = 0.9;
  EXPECT_NE(structure_key(study::make_structure(study.structure(), config.parent_path())),
            structure_key(whole));
  study.mutable_motion()->set_duration(2.0);
  const study::PreparedStudy changed = study::prepare_study(study, config.parent_path());
  const std::optional<BenchmarkEvaluation> evaluation =
      evaluate_benchmark(changed, run_study(changed, {}));
  ASSERT_TRUE(evaluation.has_value());
  const std::string table = benchmark_table(*evaluation);
  EXPECT_EQ(table.find("published (sample_controller)"), std::string::npos) << table;
  EXPECT_NE(table.find("and structure are not the ones"), std::string::npos) << table;
  EXPECT_NE(table.find("this run's motion sha256 " + evaluation->run_motion_key), std::string::npos)
      << table;
}

// rths's compensators in front of the sample controller (configs/benchmark/case_1_compensated):
// each takes the tracking error down to the sensor noise's floor (the noise alone gives J2 of
// about 2.5 %) and J1 to within a sample of zero.
TEST(BenchmarkEvaluation, CompensatorsInFrontOfTheSampleControllerReachTheNoiseFloor) {
  const std::filesystem::path config =
      std::filesystem::path(RTHS_SOURCE_DIR) / "configs/benchmark/case_1_compensated.textproto";
  config::Study study = study::load_study(config);
  study.mutable_motion()->set_duration(20.0);  // the strong motion; ATS fits every step
  const study::PreparedStudy prepared = study::prepare_study(study, config.parent_path());
  const std::optional<BenchmarkEvaluation> evaluation =
      evaluate_benchmark(prepared, run_study(prepared, {}));
  ASSERT_TRUE(evaluation.has_value());
  ASSERT_EQ(evaluation->cases.size(), 4u);
  EXPECT_GT(evaluation->cases[0].criteria.J(2), 10.0);  // the sample controller alone
  // Cut to 20 s, the motion is not the published one: no case is compared with Table 3.
  EXPECT_FALSE(evaluation->published_motion_matches);
  for (const BenchmarkCaseCriteria& c : evaluation->cases)
    EXPECT_FALSE(evaluation->compared_with_published(c)) << c.name;
  for (std::size_t c = 1; c < evaluation->cases.size(); ++c) {
    const core::BenchmarkCriteria& j = evaluation->cases[c].criteria;
    EXPECT_LT(std::abs(j.J(1)), 1.0 / 4096) << evaluation->cases[c].name;
    EXPECT_LT(j.J(2), 3.0) << evaluation->cases[c].name;
    EXPECT_LT(j.J(4), 3.5) << evaluation->cases[c].name;
  }
}

}  // namespace
}  // namespace rths::analysis
