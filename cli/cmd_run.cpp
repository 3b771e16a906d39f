// `rths run CONFIG`: every case of a study, in process; results (CSV, MATLAB or HDF5), plots and a
// summary.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "analysis/benchmark_evaluation.h"
#include "analysis/benchmark_perturbation.h"
#include "analysis/study_run.h"
#include "cli/commands.h"
#include "cli/support.h"
#include "core/study.h"
#include "tables/results.h"
#include "tables/write.h"
#include "util/atomic_file.h"

namespace rths::cli {
namespace {

struct RunOptions {
  std::string config;
  std::string out;
  std::string format = "csv";
  std::string motion_units;
  bool json = false, no_plots = false, allow_unstable = false;
  int perturbed = 0;
  std::uint64_t perturbed_seed = 1;
};

// N perturbed-plant draws of the benchmark (analysis/benchmark_perturbation.h), each run in
// process like the nominal one: J1-J9 per case as mean +- std, printed and in
// benchmark_perturbed.json.
void run_perturbed(const config::Study& study, const std::filesystem::path& base_dir,
                   const RunOptions& o, const std::filesystem::path& out) {
  if (!study.has_benchmark())
    throw std::invalid_argument(
        "--perturbed: the study has no benchmark section (the criteria to report)");
  const std::vector<analysis::PlantDraw> draws = analysis::draw_benchmark_plants(
      o.perturbed, o.perturbed_seed, analysis::experimental_stiffness(study));
  std::vector<analysis::BenchmarkEvaluation> evaluations;
  for (const analysis::PlantDraw& draw : draws) {
    const core::PreparedStudy prepared =
        core::prepare_study(analysis::perturbed_study(study, draw), base_dir);
    const analysis::StudyOutcome outcome = analysis::run_study(prepared, {.warn = print_warning});
    evaluations.push_back(*analysis::evaluate_benchmark(prepared, outcome));
  }
  const std::vector<analysis::CriteriaSpread> spread = analysis::criteria_spread(evaluations);
  util::AtomicFile json(out / "benchmark_perturbed.json");
  json.stream() << analysis::spread_json(spread, o.perturbed_seed).dump(2) << "\n";
  json.commit();
  if (!o.json)
    std::cout << analysis::spread_table(spread, o.perturbed_seed)
              << "written: benchmark_perturbed.json\n";
}

void run(const RunOptions& o) {
  const std::filesystem::path config_path = o.config;
  config::Study study = load_config_as<config::Study>(config_path, "study", core::load_study);
  if (!o.motion_units.empty())
    study.mutable_motion()->set_column_units(core::units_from_name(o.motion_units));
  const core::PreparedStudy prepared = core::prepare_study(study, config_path.parent_path());
  const analysis::StudyOutcome outcome = analysis::run_study(prepared, {.warn = print_warning});

  std::filesystem::path out = o.out;
  if (out.empty()) out = study.output().directory();
  if (out.empty())
    out = std::filesystem::path("out") / (study.name().empty() ? "study" : study.name());
  write_study_outputs(outcome, out, !o.no_plots, o.json, o.format);
  if (const auto benchmark = analysis::evaluate_benchmark(prepared, outcome)) {
    util::AtomicFile text(out / "benchmark.txt");
    text.stream() << analysis::benchmark_table(*benchmark);
    text.commit();
    util::AtomicFile json(out / "benchmark.json");
    json.stream() << analysis::benchmark_json(*benchmark).dump(2) << "\n";
    json.commit();
    if (!o.json)
      std::cout << analysis::benchmark_table(*benchmark)
                << "written: benchmark.txt, benchmark.json\n";
  }
  if (o.perturbed > 0) run_perturbed(study, config_path.parent_path(), o, out);
  fail_if_unstable(outcome, o.allow_unstable);
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run every case of a study config in process");
  cmd->add_option("config", options->config, "study config (Protobuf text format)")->required();
  cmd->add_option("--out", options->out,
                  "output folder (default: the config's output.directory, else out/<name>)");
  cmd->add_option("--format", options->format,
                  "results file: csv (results.csv), mat (MATLAB) or h5 (HDF5)")
      ->check(CLI::IsMember({"csv", "mat", "h5"}));
  cmd->add_flag("--json", options->json, "print the summary as JSON");
  cmd->add_flag("--no-plots", options->no_plots,
                "skip the PNG plots (and remove those of an earlier run)");
  cmd->add_option("--motion-units", options->motion_units,
                  "units of the motion record: g | m/s2 | cm/s2 (overrides motion.column_units; "
                  "AT2 files are in g)")
      ->check(CLI::IsMember({"g", "m/s2", "cm/s2"}));
  cmd->add_flag("--allow-unstable", options->allow_unstable,
                "a diverged case does not fail the run (exit 0); the summary still says diverged");
  cmd->add_option("--perturbed", options->perturbed,
                  "also run N perturbed benchmark plants (beta1, beta2, a3, k_e drawn as the "
                  "benchmark draws "
                  "them) and report J1-J9 as mean +- std; needs the study's benchmark section")
      ->check(in_range(core::Quantity::kCount));
  cmd->add_option("--perturbed-seed", options->perturbed_seed,
                  "seed of the perturbed draws (default 1)");
  cmd->callback([options] { run(*options); });
}

}  // namespace rths::cli
