// The RTHS benchmark's figures (analysis/benchmark/benchmark_plots.h) for its case 1: J1-J9 with the
// published values, and the two floors other than the experimental one against the exact response.
#include "analysis/benchmark/benchmark_plots.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "study/study.h"

namespace rths::analysis {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(BenchmarkPlots, CaseOneDrawsEveryCriterionAndBothOtherFloors) {
  const fs::path config = fs::path(RTHS_SOURCE_DIR) / "configs" / "benchmark" / "case_1.textproto";
  const study::PreparedStudy prepared =
      study::prepare_study(study::load_study(config), config.parent_path());
  const StudyOutcome outcome = run_study(prepared, {});
  const std::optional<BenchmarkEvaluation> evaluation = evaluate_benchmark(prepared, outcome);
  ASSERT_TRUE(evaluation.has_value());
  const fs::path dir =
      fs::temp_directory_path() / ("rths_benchmark_plots_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto written = write_benchmark_plots(*evaluation, outcome, dir);
  ASSERT_EQ(written.size(), 2u);
  for (const std::string& name : benchmark_plot_files())
    EXPECT_GT(fs::file_size(dir / name), 1000u) << name;

  const std::string criteria = read(dir / "benchmark_criteria.svg");
  for (const char* label : {">J1<", ">J2<", ">J5<", ">J9<", "J1 (ms)", "J (%)"})
    EXPECT_NE(criteria.find(label), std::string::npos) << label;
  EXPECT_NE(criteria.find("published (" + evaluation->published_case + ")"), std::string::npos)
      << "the published values apply to case 1's own motion and structure";
  for (const auto& c : evaluation->cases)
    EXPECT_NE(criteria.find(c.name), std::string::npos) << c.name;

  // Case 1's experimental storey is floor 1: the figure draws floors 2 and 3, the exact response
  // of the whole structure on each.
  ASSERT_EQ(evaluation->experimental_dof, 0);
  const std::string floors = read(dir / "benchmark_floors.svg");
  EXPECT_NE(floors.find("floor 2 (the experimental storey is floor 1)"), std::string::npos);
  EXPECT_NE(floors.find("floor 3 (the experimental storey is floor 1)"), std::string::npos);
  EXPECT_EQ(floors.find("floor 1 ("), std::string::npos);
  EXPECT_NE(floors.find("exact response of the whole structure"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rths::analysis
