// `rths run CONFIG`: every case of a study, in process; results (CSV, MATLAB or HDF5), plots and a summary.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

#include "analysis/atomic_file.h"
#include "analysis/study_run.h"
#include "cli/commands.h"
#include "core/study.h"
#include "tables/results.h"
#include "tables/write.h"

namespace rths::cli {
namespace {

struct RunOptions {
  std::string config;
  std::string out;
  std::string format = "csv";
  bool json = false, no_plots = false;
};

void run(const RunOptions& o) {
  const std::filesystem::path config_path = o.config;
  const config::Study study = core::load_study(config_path);
  const core::PreparedStudy prepared = core::prepare_study(study, config_path.parent_path());
  const analysis::StudyOutcome outcome = analysis::run_study(prepared);

  std::filesystem::path out = o.out;
  if (out.empty()) out = study.output().directory();
  if (out.empty()) out = std::filesystem::path("out") / (study.name().empty() ? "study" : study.name());
  const std::filesystem::path results = out / ("results" + tables::extension(tables::parse_format(o.format)));
  tables::write_table(tables::study_table(outcome), results, tables::parse_format(o.format));
  const bool plots = !o.no_plots;
  if (plots) analysis::write_study_plots(outcome, out);
  const nlohmann::json summary = analysis::study_summary_json(outcome);
  {
    analysis::AtomicFile json_file(out / "summary.json");
    json_file.stream() << summary.dump(2) << "\n";
    json_file.commit();
    analysis::AtomicFile text_file(out / "summary.txt");
    text_file.stream() << analysis::study_summary_text(outcome);
    text_file.commit();
  }
  if (o.json) {
    std::cout << summary.dump(2) << "\n";
  } else {
    std::cout << analysis::study_summary_text(outcome) << "written: " << results.string()
              << (plots ? ", displacement.png, force_displacement.png" : "") << ", summary.txt\n";
  }
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run every case of a study config in process");
  cmd->add_option("config", options->config, "study config (Protobuf text format)")->required();
  cmd->add_option("--out", options->out, "output folder (default: the config's output.directory, else out/<name>)");
  cmd->add_option("--format", options->format, "results file: csv (results.csv), mat (MATLAB) or h5 (HDF5)")
      ->check(CLI::IsMember({"csv", "mat", "h5"}));
  cmd->add_flag("--json", options->json, "print the summary as JSON");
  cmd->add_flag("--no-plots", options->no_plots, "skip the PNG plots");
  cmd->callback([options] { run(*options); });
}

}  // namespace rths::cli
