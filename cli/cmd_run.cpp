// `rths run CONFIG`: every case of a study, in process; results (CSV, MATLAB or HDF5), plots and a
// summary.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "analysis/benchmark/benchmark_evaluation.h"
#include "analysis/benchmark/benchmark_perturbation.h"
#include "analysis/study_run/study_run.h"
#include "analysis/tables/result_tables.h"
#include "cli/commands.h"
#include "cli/support.h"
#include "core/benchmark_criteria.h"
#include "core/number_text.h"
#include "results/results.h"
#include "results/write.h"
#include "runtime/node/plan.h"
#include "study/study.h"
#include "util/atomic_file.h"

namespace rths::cli {
namespace {

struct RunOptions {
  std::string config;
  ResultsOptions results;
  std::string motion_units;
  int perturbed = 0;
  std::uint64_t perturbed_seed = 1;
};

// Every draw, one row each: the drawn plant (beta1, beta2 1/s, a3 1/s, k_e N/m) and J1 (ms),
// J2-J9 (%) of every case, named <case>_J<n>_<unit>.
results::Table draws_table(const std::vector<analysis::PlantDraw>& draws,
                           const std::vector<analysis::BenchmarkEvaluation>& evaluations) {
  results::Table t;
  std::vector<double> index, beta1, beta2, a3, stiffness;
  for (std::size_t d = 0; d < draws.size(); ++d) {
    index.push_back(static_cast<double>(d + 1));
    beta1.push_back(draws[d].beta1);
    beta2.push_back(draws[d].beta2);
    a3.push_back(draws[d].a3);
    stiffness.push_back(draws[d].stiffness);
  }
  t.add_numbers("draw", "", index);
  t.add_numbers("beta1", "", beta1);
  t.add_numbers("beta2_1_per_s", "1/s", beta2);
  t.add_numbers("a3_1_per_s", "1/s", a3);
  t.add_numbers("k_e_N_per_m", "N/m", stiffness);
  if (evaluations.empty()) return t;
  const auto& definitions = core::criterion_definitions();
  for (std::size_t c = 0; c < evaluations.front().cases.size(); ++c) {
    for (int j = 1; j <= 9; ++j) {
      const core::CriterionDefinition& d = definitions[static_cast<std::size_t>(j - 1)];
      std::vector<double> values;
      for (const analysis::BenchmarkEvaluation& e : evaluations)
        values.push_back(core::reported_value(e.cases.at(c).criteria, j));
      t.add_numbers(results::identifier(evaluations.front().cases[c].name) + "_" + d.name + "_" +
                        results::unit_suffix(d.unit),
                    d.unit, values);
    }
  }
  return t;
}

// N perturbed-plant draws of the benchmark (analysis/benchmark/benchmark_perturbation.h), each run in
// process like the nominal one: J1-J9 per case as mean +- std, printed and in
// benchmark_perturbed.json; every draw in benchmark_perturbed.csv (draws_table).
void run_perturbed(const config::Study& study, const std::filesystem::path& base_dir,
                   const RunOptions& o, const std::filesystem::path& out) {
  if (!study.has_benchmark())
    throw std::invalid_argument(
        "--perturbed: the study has no benchmark section (the criteria to report)");
  const std::vector<analysis::PlantDraw> draws = analysis::draw_benchmark_plants(
      o.perturbed, o.perturbed_seed, analysis::experimental_stiffness(study));
  std::vector<analysis::BenchmarkEvaluation> evaluations;
  for (const analysis::PlantDraw& draw : draws) {
    const study::PreparedStudy prepared =
        study::prepare_study(analysis::perturbed_study(study, draw), base_dir);
    const analysis::StudyOutcome outcome = analysis::run_study(prepared, {.warn = print_warning});
    evaluations.push_back(*analysis::evaluate_benchmark(prepared, outcome));
  }
  const std::vector<analysis::CriteriaSpread> spread = analysis::criteria_spread(evaluations);
  util::AtomicFile json(out / "benchmark_perturbed.json");
  json.stream() << analysis::spread_json(spread, o.perturbed_seed).dump(2) << "\n";
  json.commit();
  results::write_table(draws_table(draws, evaluations), out / "benchmark_perturbed.csv",
                       results::Format::kCsv);
  if (!o.results.json)
    std::cout << analysis::spread_table(spread, o.perturbed_seed)
              << "written: benchmark_perturbed.json, benchmark_perturbed.csv (every draw)\n";
}

// The run's cost, one line after the summary: set-up (the config read, the structure built and
// split, its damping, the motion: everything before the first case) in s, and the cases' run
// (each case's checks, integrator set-up, steps and record, end to end) as its total over the
// steps taken by every case: "timing: set-up S s; C cases, N steps in R s: P us a step end to end"
// with P = R / N (1e6 us/s). steady_clock, wall time. Not with --json: its output is the JSON.
void print_timing(double setup_s, double run_s, const analysis::StudyOutcome& outcome,
                  std::ostream& out) {
  std::size_t steps = 0;
  for (const analysis::CaseOutcome& c : outcome.cases) steps += c.simulation.steps();
  out << "timing: set-up " << core::format_number(setup_s) << " s; " << outcome.cases.size()
      << " cases, " << steps << " steps in " << core::format_number(run_s)
      << " s: " << core::format_number(steps > 0 ? 1e6 * run_s / static_cast<double>(steps) : 0.0)
      << " us a step end to end\n";
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Before any case runs: the default recorders' line (with --json on stderr, whose stdout is the
// JSON), and a CSV past a spreadsheet's size refused (results/write.h).
void require_table_fits(const study::PreparedStudy& prepared, const ResultsOptions& results) {
  if (!prepared.recorders.defaults.empty())
    (results.json ? std::cerr : std::cout) << prepared.recorders.defaults << "\n";
  if (results::parse_format(results.format) != results::Format::kCsv) return;
  const analysis::TableShape shape = analysis::study_table_shape(
      prepared.recorders, prepared.motion.acceleration.size(),
      static_cast<std::size_t>(std::max(1, prepared.config.cases_size())),
      prepared.base.partition.actuator_storeys.size());
  results::require_spreadsheet_size(shape.rows, shape.columns, "results.csv");
}

void run(const RunOptions& o) {
  const auto started = std::chrono::steady_clock::now();
  const std::filesystem::path config_path = o.config;
  config::Study study = load_config_as<config::Study>(config_path, "study", study::load_study);
  if (!o.motion_units.empty())
    study.mutable_motion()->set_column_units(study::units_from_name(o.motion_units));
  const study::PreparedStudy prepared = study::prepare_study(study, config_path.parent_path());
  runtime::check_deployment(prepared);  // the deployment `launch` would run is refused here too
  std::filesystem::path out = o.results.out;
  if (out.empty()) out = study.output().directory();
  if (out.empty())
    out = std::filesystem::path("out") / (study.name().empty() ? "study" : study.name());
  claim_output_folder(out, study.name(), o.results.force);
  require_table_fits(prepared, o.results);
  const double setup_s = seconds_since(started);
  const auto cases_started = std::chrono::steady_clock::now();
  // A run longer than a few seconds says how far it is on stderr (analysis/study_run/run_progress.h).
  const analysis::StudyOutcome outcome = analysis::run_study(
      prepared, {.warn = print_warning, .progress = {.print = [](const std::string& line) {
                                          std::cerr << "rths: " << line << "\n";
                                        }}});
  const double run_s = seconds_since(cases_started);
  write_study_outputs(outcome, out, !o.results.no_plots, o.results.json, o.results.format);
  write_benchmark_outputs(prepared, outcome, out, !o.results.no_plots, o.results.json);
  if (!o.results.json) print_timing(setup_s, run_s, outcome, std::cout);
  if (o.perturbed > 0) run_perturbed(study, config_path.parent_path(), o, out);
  fail_if_unstable(outcome, o.results.allow_unstable);
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run every case of a study config in process");
  cmd->add_option("config", options->config, "study config (Protobuf text format)")->required();
  add_results_options(cmd, options->results,
                      "output folder (default: the config's output.directory, else out/<name>)",
                      "");
  cmd->add_option("--motion-units", options->motion_units,
                  "units of the motion record: g | m/s2 | cm/s2 | in/s2 | mm/s2 (overrides "
                  "motion.column_units; an AT2 file is read in its header's units, and one that "
                  "disagrees is refused)")
      ->check(CLI::IsMember({"g", "m/s2", "cm/s2", "in/s2", "mm/s2"}));
  cmd->add_option("--perturbed", options->perturbed,
                  "also run N perturbed benchmark plants (beta1, beta2, a3, k_e drawn as the "
                  "benchmark draws "
                  "them) and report J1-J9 as mean +- std; needs the study's benchmark section")
      ->check(in_range(study::Quantity::kCount));
  cmd->add_option("--perturbed-seed", options->perturbed_seed,
                  "seed of the perturbed draws (default 1)");
  cmd->footer("A study with a benchmark section is also judged by the " +
              core::criteria_glossary() +
              "(benchmark.txt, benchmark.json: each criterion as {name, value, unit, definition})");
  cmd->callback([options] { run(*options); });
}

}  // namespace rths::cli
