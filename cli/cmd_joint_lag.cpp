// `rths joint-lag CONFIG`: the network lag x actuator lag study (see analysis/joint_lag/joint_lag.h; its
// across-sites runs: deploy/joint_lag_sites.h).
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

#include "analysis/joint_lag/joint_lag.h"
#include "cli/commands.h"
#include "cli/support.h"
#include "deploy/joint_lag_sites.h"

namespace rths::cli {
namespace {

struct JointLagOptions {
  std::string config, out;
  bool json = false, no_plots = false, no_measure = false, allow_unstable = false;
};

void run(const JointLagOptions& o) {
  const std::filesystem::path path = o.config;
  const auto config =
      load_config_as<analysis::JointLagStudy>(path, "joint-lag study", analysis::load_joint_lag);
  analysis::JointLagOptions options;
  if (!o.out.empty()) options.output_directory = std::filesystem::path(o.out);
  options.measure = !o.no_measure;
  options.plots = !o.no_plots;
  options.across_sites = deploy::joint_lag_across_sites();
  ProgressReporter progress("joint-lag", "points", !o.json);
  options.progress = [&progress](std::size_t done, std::size_t total) {
    progress.update(done, total);
  };
  options.warn = print_warning;
  const auto result = analysis::run_joint_lag(config, path.parent_path(), options);
  analysis::write_joint_lag_outputs(result, options.plots);
  if (o.json) {
    std::cout << analysis::to_json(result).dump(2) << "\n";
  } else {
    std::cout << analysis::to_text(result);
  }
  // The one rule of every command: a diverged point fails the run unless it is meant.
  if (const std::size_t diverged = analysis::diverged_points(result);
      diverged > 0 && !o.allow_unstable && !config.expect_unstable()) {
    throw ExitError(kExitRunFailed,
                    std::to_string(diverged) + " of " +
                        std::to_string(result.grid.size() + result.measured.size()) +
                        " joint-lag points diverged (marked in grid.csv and the map); "
                        "--allow-unstable, or expect_unstable: true in the joint-lag study, when "
                        "that is meant");
  }
}

}  // namespace

void add_joint_lag_command(CLI::App& app) {
  auto options = std::make_shared<JointLagOptions>();
  CLI::App* cmd = app.add_subcommand(
      "joint-lag",
      "Sweep network lag x actuator lag: error surface, measured total lag vs injected parts; "
      "optionally real runs across namespace sites (root)");
  cmd->add_option("config", options->config, "joint lag config (rths.analysis.JointLagStudy)")
      ->required();
  cmd->add_option("--out", options->out, "output folder (default: the config's)");
  cmd->add_flag("--json", options->json, "print the summary as JSON");
  cmd->add_flag("--no-plots", options->no_plots, "skip the PNG plots");
  cmd->add_flag("--no-measure", options->no_measure, "skip the across-sites runs");
  cmd->add_flag("--allow-unstable", options->allow_unstable,
                "diverged points do not fail the run (exit 0); they are still marked");
  cmd->callback([options] { run(*options); });
}

}  // namespace rths::cli
