// What the plots cost against the run, as `rths run` spends it: the study run in process and its
// results table written (what --no-plots does), then the figures (displacement, force against
// displacement) drawn. Prints both times (s, wall clock) and their ratio with plots / without,
// against issue 39's target of at most 2x. A benchmark: prints figures, never part of the suite.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "analysis/study_run.h"
#include "results/results.h"
#include "results/write.h"
#include "study/study.h"

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void measure(const std::string& relative_config) {
  using namespace rths;
  const std::filesystem::path config = std::filesystem::path(RTHS_SOURCE_DIR) / relative_config;
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("rths_plots_bench_" + config.stem().string());
  std::filesystem::create_directories(out);
  const auto start = std::chrono::steady_clock::now();
  const core::PreparedStudy prepared =
      core::prepare_study(core::load_study(config), config.parent_path());
  const analysis::StudyOutcome outcome = analysis::run_study(prepared);
  results::write_table(results::study_table(outcome), out / "results.csv", results::Format::kCsv);
  const double run = seconds_since(start);
  const auto plotting = std::chrono::steady_clock::now();
  analysis::write_study_plots(outcome, out);
  const double plots = seconds_since(plotting);
  const double ratio = (run + plots) / run;
  std::printf(
      "%-40s --no-plots %7.2f s, with plots %7.2f s (plots %6.2f s): %.2fx (target <= 2x: "
      "%s)\n",
      relative_config.c_str(), run, run + plots, plots, ratio, ratio <= 2.0 ? "met" : "MISSED");
  std::filesystem::remove_all(out);
}

}  // namespace

int main() {
  measure("configs/benchmark/case_1.textproto");
  measure("configs/paper_frame.textproto");
  return 0;
}
