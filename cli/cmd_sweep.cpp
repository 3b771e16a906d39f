// `rths sweep CONFIG`: the paper's Fig. 4 grid on every core; `rths sweep merge` joins shards.
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>

#include "analysis/sweep/sweep_csv.h"
#include "analysis/sweep/sweep_grid.h"
#include "analysis/sweep/sweep_report.h"
#include "analysis/sweep/sweep_run.h"
#include "analysis/tables/result_tables.h"
#include "cli/commands.h"
#include "cli/support.h"
#include "results/results.h"
#include "results/write.h"
#include "slurm/sbatch.h"
#include "study/study.h"
#include "util/distinct_paths.h"
#include "util/parallel_for.h"

namespace rths::cli {
namespace {

struct SweepOptions {
  std::string config, out, shard;
  std::string format = "csv";  // csv | mat | h5; shards are always CSV (merge joins CSVs)
  std::string slurm;           // job folder: write Slurm scripts instead of running
  slurm::SweepJob job;         // --shards, --partition, --time, --mem of the Slurm job
  int threads = 0;
  bool json = false, no_plots = false, general = false, allow_unstable = false;
};

struct MergeOptions {
  std::string out;
  std::vector<std::string> shards;
  bool json = false, no_plots = false;
};

void print_trends(const std::vector<analysis::SweepTableRow>& table) {
  const analysis::SweepTrends t = analysis::measure_trends(table, analysis::SweepMeasure::kErms);
  std::cout << "stiffness at fixed period: max relative E_rms difference "
            << t.stiffness_max_relative_difference << "\n"
            << "error vs period: E_rms falls between "
            << (std::isfinite(t.period_falling_fraction) ? 100 * t.period_falling_fraction : 0.0)
            << " % of consecutive periods\n";
  if (std::isfinite(t.nonlinear_to_linear_median_ratio)) {
    std::cout << "non-linear / linear E_rms at the same initial period (median): "
              << t.nonlinear_to_linear_median_ratio << "\n";
  }
  if (t.diverged_points) std::cout << "diverged points: " << t.diverged_points << "\n";
}

void write_plot(const std::vector<analysis::SweepTableRow>& table, const std::filesystem::path& png,
                const std::string& title, const analysis::CriticalDelayOf& critical_delay = {}) {
  try {
    analysis::write_sweep_plot(table, png, title, critical_delay);
  } catch (const std::invalid_argument& e) {
    std::cerr << "rths sweep: no plot: " << e.what() << "\n";  // e.g. only zero delays swept
  } catch (const std::runtime_error& e) {
    throw ExitError(kExitEnvironment,
                    std::string("the CSV is written, the plot failed: ") + e.what());
  }
}

void warn_points_past_critical(const analysis::SweepGrid& grid) {
  const analysis::SweepStabilityCheck stability = analysis::check_sweep_stability(grid);
  if (stability.past == 0) return;
  std::ostringstream warning;
  warning << stability.past << " of " << stability.combinations
          << " (period, fraction, dt, delay) points are past their critical delay; the worst: "
          << stability.worst;
  print_warning(warning.str());
}

// Where the sweep's table goes: out/sweep.<format>, or out/sweep.shard-I-of-N.csv for a shard.
std::filesystem::path sweep_table_path(const SweepOptions& o, const config::Study& study,
                                       const analysis::Shard& shard, results::Format format) {
  std::filesystem::path out = o.out;
  if (out.empty()) out = study.output().directory();
  if (out.empty())
    out = std::filesystem::path("out") / (study.name().empty() ? "sweep" : study.name());
  const bool sharded = shard.count > 1;
  if (sharded && format != results::Format::kCsv) {
    throw ExitError(
        kExitBadInput,
        "sweep --shard writes CSV (`rths sweep merge` joins CSVs); drop --format " + o.format);
  }
  return out / (sharded ? "sweep.shard-" + std::to_string(shard.index) + "-of-" +
                              std::to_string(shard.count) + ".csv"
                        : "sweep" + results::extension(format));
}

void write_sweep_table(const std::filesystem::path& path, results::Format format,
                       const analysis::SweepGrid& grid, const analysis::Shard& shard,
                       const std::vector<analysis::SweepRow>& rows,
                       const std::vector<analysis::SweepTableRow>& table) {
  try {
    // The CSV keeps its own writer: its first line carries the grid hash and shard that merge
    // checks.
    if (format == results::Format::kCsv) {
      analysis::write_sweep_csv(path, grid, shard, rows);
    } else {
      results::write_table(analysis::sweep_table(table, grid.hash_hex(), grid.size()), path,
                           format);
    }
  } catch (const std::exception& e) {
    throw ExitError(kExitEnvironment, e.what());
  }
}

struct SweepOutcome {
  std::filesystem::path csv, png;
  bool plot = false;
  std::size_t points_run = 0;
  double seconds = 0;
};

void report_sweep(const SweepOptions& o, const analysis::SweepGrid& grid,
                  const analysis::Shard& shard, const SweepOutcome& r,
                  const std::vector<analysis::SweepTableRow>& table) {
  if (o.json) {
    nlohmann::json summary = {{"csv", r.csv.string()},
                              {"plot", r.plot ? nlohmann::json(r.png.string()) : nlohmann::json()},
                              {"grid_hash", grid.hash_hex()},
                              {"grid_points", grid.size()},
                              {"shard", shard.to_string()},
                              {"points_run", r.points_run},
                              {"threads", util::resolve_threads(o.threads)},
                              {"seconds", r.seconds}};
    summary.update(analysis::sweep_trends_json(table));
    std::cout << summary.dump(2) << "\n";
    return;
  }
  std::cout << "sweep " << shard.to_string() << ": " << r.points_run << " of " << grid.size()
            << " points in " << r.seconds << " s (grid " << grid.hash_hex() << ")\n";
  if (shard.count <= 1) print_trends(table);
  std::cout << "written: " << r.csv.string() << ", " << analysis::sweep_sidecar_path(r.csv).string()
            << (r.plot ? ", " + r.png.string() + "/.svg, " +
                             analysis::sweep_delay_plot_path(r.png).string() + "/.svg"
                       : std::string())
            << "\n";
}

void run_sweep_command(const SweepOptions& o) {
  if (o.config.empty())
    throw ExitError(kExitBadInput, "sweep: give a CONFIG, or use `rths sweep merge`");
  const std::filesystem::path config_path = o.config;
  const config::Study study =
      load_config_as<config::Study>(config_path, "study", study::load_study);
  const analysis::SweepGrid grid(study, config_path.parent_path(), config_path.string());
  analysis::SweepOptions options;
  if (!o.shard.empty()) options.shard = analysis::parse_shard(o.shard);
  options.threads = o.threads;
  options.general_path_only = o.general;
  warn_points_past_critical(grid);
  ProgressReporter progress("sweep", "points");
  options.progress = [&progress](std::size_t done, std::size_t total) {
    progress.update(done, total);
  };
  const results::Format format = results::parse_format(o.format);
  SweepOutcome r;
  r.csv = sweep_table_path(o, study, options.shard, format);

  const auto start = std::chrono::steady_clock::now();
  const std::vector<analysis::SweepRow> rows = analysis::run_sweep(grid, options);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.points_run = rows.size();
  const std::vector<analysis::SweepTableRow> table = analysis::to_table(grid, rows);
  write_sweep_table(r.csv, format, grid, options.shard, rows, table);
  r.png = r.csv.parent_path() / "sweep.png";
  r.plot = !o.no_plots && options.shard.count <= 1 && !rows.empty();
  if (r.plot)
    write_plot(table, r.png, study.name().empty() ? "sweep" : study.name(),
               analysis::critical_delay_of(grid));
  report_sweep(o, grid, options.shard, r, table);
  const std::size_t diverged = static_cast<std::size_t>(std::count_if(
      rows.begin(), rows.end(), [](const analysis::SweepRow& row) { return row.diverged; }));
  if (diverged > 0 && !o.allow_unstable && !study.sweep().expect_unstable()) {
    throw ExitError(kExitRunFailed,
                    std::to_string(diverged) + " of " + std::to_string(rows.size()) +
                        " sweep points diverged (marked in the CSV and the plot); "
                        "--allow-unstable, or sweep { expect_unstable: true }, when that is meant");
  }
}

// Writes the Slurm array and merge scripts for the sweep; checks the grid first so a bad config
// fails here, not on the cluster.
void write_slurm_job(const SweepOptions& o) {
  const std::filesystem::path config_path = std::filesystem::absolute(o.config);
  const config::Study study = study::load_study(config_path);
  const analysis::SweepGrid grid(study, config_path.parent_path(), config_path.string());
  slurm::SweepJob job = o.job;
  job.rths = std::filesystem::read_symlink("/proc/self/exe");
  job.config = config_path;
  job.out = std::filesystem::absolute(o.slurm);
  job.threads = o.threads > 0 ? o.threads : 1;
  if (job.shards > grid.size()) {
    throw ExitError(kExitBadInput, "--shards " + std::to_string(job.shards) +
                                       " is more than the grid's " + std::to_string(grid.size()) +
                                       " points");
  }
  std::vector<std::filesystem::path> written;
  try {
    written = slurm::write_sweep_job(job);
  } catch (const std::invalid_argument&) {
    throw;
  } catch (const std::exception& e) {
    throw ExitError(kExitEnvironment, e.what());
  }
  std::cout << "Slurm job for " << grid.size() << " points in " << job.shards
            << " array tasks: " << written[0].string() << ", merge: " << written[1].string() << "\n"
            << "submit with: bash " << written[2].string()
            << "  (merged CSV: " << (job.out / "sweep.csv").string() << ")\n";
}

void run_merge_command(const MergeOptions& o) {
  std::vector<std::filesystem::path> shards(o.shards.begin(), o.shards.end());
  std::vector<util::NamedPath> inputs;
  for (const auto& shard : shards) inputs.push_back({"shard", shard});
  util::refuse_output_over_input({"out", o.out}, inputs);
  const analysis::SweepCsv merged = analysis::merge_sweep_csvs(shards, o.out);
  const std::vector<analysis::SweepTableRow> table = analysis::parse_sweep_rows(merged, o.out);
  std::filesystem::path png = o.out;
  png.replace_extension(".png");
  const bool plot = !o.no_plots && !table.empty();
  if (plot) write_plot(table, png, "sweep " + merged.grid_hash);
  if (o.json) {
    nlohmann::json summary{{"csv", o.out},
                           {"plot", plot ? nlohmann::json(png.string()) : nlohmann::json()},
                           {"grid_hash", merged.grid_hash},
                           {"grid_points", merged.points},
                           {"shards", o.shards.size()}};
    summary.update(analysis::sweep_trends_json(table));
    std::cout << summary.dump(2) << "\n";
    return;
  }
  std::cout << "merged " << o.shards.size() << " shards: " << merged.points << " points (grid "
            << merged.grid_hash << ")\n";
  print_trends(table);
  std::cout << "written: " << o.out << (plot ? ", " + png.string() + "/.svg" : std::string())
            << "\n";
}

}  // namespace

void add_sweep_command(CLI::App& app) {
  auto options = std::make_shared<SweepOptions>();
  auto merge = std::make_shared<MergeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "The paper's Fig. 4 study: error vs period over a grid of periods, delays, "
      "experimental fractions, stiffnesses, dt, records and restoring models");
  cmd->add_option("config", options->config,
                  "study config with a `sweep` block (Protobuf text format)");
  cmd->add_option("--shard", options->shard,
                  "run slice i of N (0-based, contiguous blocks of the grid) and write "
                  "sweep.shard-i-of-N.csv; join the slices with `rths sweep merge`");
  cmd->add_option("--out", options->out,
                  "output folder (default: the config's output.directory, else out/<name>)");
  cmd->add_option("--threads", options->threads, "worker threads (default: every core)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--format", options->format,
                  "sweep.csv, sweep.mat (MATLAB) or sweep.h5 (HDF5); shards are CSV")
      ->check(CLI::IsMember({"csv", "mat", "h5"}));
  cmd->add_flag("--json", options->json, "print the summary as JSON");
  cmd->add_flag("--no-plots", options->no_plots, "skip the PNG plot");
  cmd->add_option(
      "--slurm", options->slurm,
      "write a Slurm job into this folder instead of running: an sbatch array (one task per "
      "shard) and a merge job after it; submit with `bash FOLDER/submit.sh`");
  cmd->add_option("--shards", options->job.shards, "--slurm: array tasks (default 4)")
      ->check(in_range(study::Quantity::kCount));
  cmd->add_option("--partition", options->job.partition,
                  "--slurm: partition (default: the cluster's)");
  cmd->add_option("--time", options->job.time,
                  "--slurm: time limit per task, e.g. 30 or 02:00:00 (default 01:00:00)");
  cmd->add_option("--mem", options->job.memory,
                  "--slurm: memory per task, e.g. 500M or 2G (default 1G)");
  cmd->add_flag("--allow-unstable", options->allow_unstable,
                "diverged points do not fail the sweep (exit 0); they are still marked");
  cmd->add_flag("--general", options->general,
                "run every point through the general simulator (no SIMD batch kernel)");

  CLI::App* merge_cmd = cmd->add_subcommand(
      "merge",
      "Join shard CSVs of one grid into a complete CSV (and its plot); refuses shards of "
      "another grid, duplicates and gaps");
  merge_cmd->add_option("out", merge->out, "merged CSV to write")->required();
  merge_cmd->add_option("shards", merge->shards, "shard CSVs")->required();
  merge_cmd->add_flag("--json", merge->json, "print the summary as JSON");
  merge_cmd->add_flag("--no-plots", merge->no_plots, "skip the PNG plot");
  merge_cmd->callback([merge] { run_merge_command(*merge); });

  cmd->callback([options, merge_cmd] {
    if (merge_cmd->parsed()) return;
    if (!options->slurm.empty()) return write_slurm_job(*options);
    run_sweep_command(*options);
  });
}

}  // namespace rths::cli
