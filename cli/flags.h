#pragma once
// Flags every command reads alike: time values with units, numbers checked against their
// quantity's range rule (study/ranges.h), and the option groups of the commands that run cases
// (results) or start processes (node programs).
#include <CLI/CLI.hpp>

#include <chrono>
#include <string>

#include "runtime/node/node_main.h"
#include "study/ranges.h"

namespace rths::cli {

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
CLI::Validator seconds_in(study::Quantity quantity);
// A plain number flag checked against its quantity's range rule (counts, fractions, CPUs...).
CLI::Validator in_range(study::Quantity quantity);
// A number flag in [min, max], finite (runtime/node/node_main.h: every program's flags).
using runtime::finite_in;

}  // namespace rths::cli
