#include "cli/flags.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/number_text.h"
#include "study/text_columns.h"

namespace rths::cli {

double parse_seconds(const std::string& text) {
  std::string compact;
  for (char c : text) {
    if (!std::isspace(static_cast<unsigned char>(c))) compact += c;
  }
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(compact, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const std::string unit = used > 0 ? compact.substr(used) : "";
  double factor = 0.0;
  if (unit.empty() || unit == "s")
    factor = 1.0;
  else if (unit == "ms")
    factor = 1e-3;
  else if (unit == "us")
    factor = 1e-6;
  if (used == 0 || factor == 0.0 || !std::isfinite(value)) {
    throw std::invalid_argument("'" + text +
                                "' is not a time: give seconds (0.014), or a number with "
                                "its unit: 14ms, 0.014s, 14000us");
  }
  return value * factor;
}

std::chrono::steady_clock::time_point seconds_from_now(double seconds) {
  return std::chrono::steady_clock::now() +
         std::chrono::duration_cast<std::chrono::steady_clock::duration>(
             std::chrono::duration<double>(seconds));
}

CLI::Validator seconds_value() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        try {
          std::ostringstream out;
          out.precision(17);
          out << parse_seconds(input);
          input = out.str();
          return "";
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      },
      "TIME (s, or 14ms)");
}

namespace {
// CLI11 prefixes a validator's message with the flag ("--dt: "), so the rule's message omits it.
CLI::Validator range_validator(study::Quantity quantity, bool seconds) {
  return CLI::Validator(
      [quantity, seconds](std::string& input) -> std::string {
        double value = 0;
        if (seconds) {
          try {
            value = parse_seconds(input);
          } catch (const std::invalid_argument& e) {
            return e.what();
          }
        } else if (const auto number = core::parse_finite(input)) {
          value = *number;
        } else {
          return "'" + input + "' is not a number";
        }
        const std::string violation = study::range_violation(quantity, value, "");
        if (!violation.empty()) return violation;
        if (seconds) {
          std::ostringstream out;
          out.precision(17);
          out << value;
          input = out.str();
        }
        return "";
      },
      study::range_of(quantity).text());
}
}  // namespace

CLI::Validator seconds_in(study::Quantity quantity) { return range_validator(quantity, true); }
CLI::Validator in_range(study::Quantity quantity) { return range_validator(quantity, false); }

void add_results_options(CLI::App* cmd, ResultsOptions& options, const std::string& out_help,
                         const std::string& table_note) {
  cmd->add_option("--out", options.out, out_help);
  cmd->add_option("--format", options.format,
                  "results file: csv (results.csv), mat (MATLAB) or h5 (HDF5)" + table_note)
      ->check(CLI::IsMember({"csv", "mat", "h5"}));
  cmd->add_flag("--no-plots", options.no_plots,
                "skip the plots (those of an earlier run stay, named in the summary)");
  cmd->add_flag("--force", options.force,
                "write into an output folder that holds another study's results (overwriting)");
  cmd->add_flag("--allow-unstable", options.allow_unstable,
                "a diverged case does not fail the run (exit 0); the summary still says diverged");
  cmd->add_flag("--json", options.json, "print the summary as JSON");
}

void add_node_program_options(CLI::App* cmd, NodeProgramOptions& options) {
  cmd->add_option("--bin-dir", options.bin_dir,
                  "folder of rths-coordinator and the node programs (default: beside rths)");
  cmd->add_option("--security", options.security,
                  "DDS Security: the `rths pki init` folder (default deployment.security_dir); "
                  "each process uses its node_<id> folder");
}

}  // namespace rths::cli
