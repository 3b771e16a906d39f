#pragma once
// What every subcommand shares: loading a config of the expected kind (and naming the kind a
// mismatched file is), flag values with units, warnings, "did you mean", and the outputs and
// exit status of a study run (`run` and `sdof`).

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/study_run.h"
#include "runtime/node/node_main.h"
#include "study/ranges.h"

namespace rths::cli {

// Which kind of config a text-format file parses as: "study (rths.config.Study)", "joint-lag
// study (rths.analysis.JointLagStudy)", "sites (rths.deploy.Sites)", or empty when none.
std::string config_kind_of(const std::filesystem::path& path);

// Calls `load`; when it throws std::invalid_argument and the file parses as another kind of
// config, rethrows with "FILE is a <kind> config, not a <expected> config (use `rths <command>`)".
template <class Config>
Config load_config_as(const std::filesystem::path& path, const std::string& expected_kind,
                      const std::function<Config(const std::filesystem::path&)>& load);
void rethrow_with_config_kind(const std::filesystem::path& path, const std::string& expected_kind,
                              const std::invalid_argument& error);

// Progress of a long command on stderr: one bar redrawn at most every 0.1 s when stderr is a
// terminal; otherwise (a log, a batch job) a plain line per 10 %, so logs stay short. `label`
// starts each line ("sweep", "sites"), `unit` names what is counted ("points", "cases").
class ProgressReporter {
 public:
  ProgressReporter(std::string label, std::string unit, bool enabled = true);
  void update(std::size_t done, std::size_t total);

 private:
  std::string label_, unit_;
  bool enabled_, tty_;
  double start_seconds_;
  double last_draw_ = -1;
  int last_decile_ = 0;
};

// "rths: warning: ..." on stderr.
void print_warning(const std::string& message);

// What a command that runs cases writes and how it ends, declared once for run, launch and sites:
// --out, --format (csv | mat | h5), --no-plots, --json, --allow-unstable. `out_help` says what
// the folder holds for this command; `table_note` is added to --format's help (", the columns
// of ...").
struct ResultsOptions {
  std::string out;
  std::string format = "csv";
  bool no_plots = false, json = false, allow_unstable = false, force = false;
};
void add_results_options(CLI::App* cmd, ResultsOptions& options, const std::string& out_help,
                         const std::string& table_note);

// What starts a deployment's processes, for the commands that start them (launch, sites):
// --bin-dir (the folder of rths-coordinator and the node programs) and --security (the `rths pki
// init` folder; each process uses its node_<id> folder).
struct NodeProgramOptions {
  std::string bin_dir, security;
};
void add_node_program_options(CLI::App* cmd, NodeProgramOptions& options);

// A CLI11 transform for a time flag: "14ms", "14 ms", "0.014s", "14000us" or a bare number (s)
// become seconds; anything else is refused with a message naming the unit (s) and the forms.
CLI::Validator seconds_value();
// The same parse as a function: seconds from text. Throws std::invalid_argument.
double parse_seconds(const std::string& text);
// The steady clock's now plus `seconds` (a time flag's value): when a command's --for ends.
std::chrono::steady_clock::time_point seconds_from_now(double seconds);
// A time flag checked against its quantity's range rule (study/ranges.h): seconds_value() then
// the rule; attach with ->transform (it rewrites "14ms" to seconds); CLI11 refuses a value as
// "--dt: 1e-09 s is outside [1e-06, 1] s (...)", exit 2.
CLI::Validator seconds_in(core::Quantity quantity);
// A plain number flag checked against its quantity's range rule (counts, fractions, CPUs...).
CLI::Validator in_range(core::Quantity quantity);
// A number flag in [min, max], finite (runtime/node/node_main.h: every program's flags).
using runtime::finite_in;

// The candidate closest to `word` by edit distance, when close enough to be a slip (at most a
// third of the word's length, and at least 1 edit allowed).
std::optional<std::string> closest(const std::string& word,
                                   const std::vector<std::string>& candidates);

// Before parsing, level by level (`rths pki init ...` is three levels): an unknown subcommand or
// an unknown --flag gets "did you mean" from that level's own subcommands and flags. Returns the
// message, or empty when the words are known.
std::string suggest_for_unknown(const CLI::App& app, int argc, const char* const* argv);

// An output folder belongs to the study that first wrote it: its OUTPUT_OWNER file (kOwnerFile)
// names the study, or, in a folder written before that file, its summary.json's "study". Another
// study's folder is refused (ExitError kExitBadInput naming both studies, the folder and
// --force) unless `force`; then, or when the folder is new or this study's, the study claims it.
inline constexpr const char* kOwnerFile = ".rths-study";
void claim_output_folder(const std::filesystem::path& out, const std::string& study, bool force);

// results.csv and the plots (drawn at once; with plots off, plots of an earlier run are left in
// place and the summary names them), then summary.json/.txt; prints the summary (JSON or text)
// and "written:" with the files written. Figures that fail are a warning, not an error: the
// table and summary are written whatever gnuplot does, and the exit is the cases'.
void write_study_outputs(const analysis::StudyOutcome& outcome, const std::filesystem::path& out,
                         bool plots, bool json, const std::string& format = "csv");
// A study with a benchmark section: J1-J9 of its cases (analysis::evaluate_benchmark) written to
// out/benchmark.txt and out/benchmark.json, with `plots` its figures (analysis/benchmark_plots.h),
// and the table printed unless `quiet`. Nothing without one. The same after `rths run` and
// `rths launch`.
void write_benchmark_outputs(const core::PreparedStudy& prepared,
                             const analysis::StudyOutcome& outcome,
                             const std::filesystem::path& out, bool plots, bool quiet);
// Throws ExitError(1) listing every case that failed the run (analysis::StudyOutcome::failures).
void fail_if_unstable(const analysis::StudyOutcome& outcome, bool allow_unstable);

template <class Config>
Config load_config_as(const std::filesystem::path& path, const std::string& expected_kind,
                      const std::function<Config(const std::filesystem::path&)>& load) {
  try {
    return load(path);
  } catch (const std::invalid_argument& e) {
    rethrow_with_config_kind(path, expected_kind, e);
    throw;
  }
}

}  // namespace rths::cli
