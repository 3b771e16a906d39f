#include "cli/support.h"

#include "analysis/benchmark_plots.h"
#include "analysis/result_tables.h"
#include "results/results.h"
#include "results/write.h"

#include <fmt/format.h>
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>
#include <iostream>
#include <memory>

#include "analysis/benchmark_evaluation.h"
#include "cli/commands.h"
#include "rths/analysis/joint_lag.pb.h"
#include "rths/proto/config.pb.h"
#include "study/text_columns.h"
#include "study/text_format.h"
#include "util/atomic_file.h"
#if __has_include("rths/deploy/sites.pb.h")
#include "rths/deploy/sites.pb.h"
#define RTHS_CLI_HAS_DEPLOY 1
#endif

namespace rths::cli {
namespace {

class SilentErrors : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int, google::protobuf::io::ColumnNumber, const std::string&) override {}
};

bool parses_as(const std::string& text, google::protobuf::Message& message) {
  SilentErrors errors;
  google::protobuf::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  return parser.ParseFromString(text, &message);
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, substitution});
    }
    std::swap(previous, current);
  }
  return previous[b.size()];
}

}  // namespace

std::string config_kind_of(const std::filesystem::path& path) {
  std::string text;
  try {
    text = core::read_text_file(path, "config");
  } catch (const std::invalid_argument&) {
    return "";
  }
  config::Study study;
  if (parses_as(text, study)) return "study (rths.config.Study)";
  analysis::JointLagStudy joint;
  if (parses_as(text, joint)) return "joint-lag study (rths.analysis.JointLagStudy)";
#ifdef RTHS_CLI_HAS_DEPLOY
  deploy::Sites sites;
  if (parses_as(text, sites)) return "sites (rths.deploy.Sites)";
#endif
  return "";
}

void rethrow_with_config_kind(const std::filesystem::path& path, const std::string& expected_kind,
                              const std::invalid_argument& error) {
  const std::string kind = config_kind_of(path);
  if (kind.empty() || kind.rfind(expected_kind, 0) == 0) return;
  std::string command = "run";
  if (kind.rfind("joint-lag", 0) == 0) command = "joint-lag";
  if (kind.rfind("sites", 0) == 0) command = "sites";
  throw std::invalid_argument(path.string() + " is a " + kind + " config, not a " + expected_kind +
                              " config: try `rths " + command + " " + path.string() + "` (" +
                              error.what() + ")");
}

namespace {
double monotonic_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

ProgressReporter::ProgressReporter(std::string label, std::string unit, bool enabled)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      enabled_(enabled),
      tty_(isatty(STDERR_FILENO) != 0),
      start_seconds_(monotonic_seconds()) {}

void ProgressReporter::update(std::size_t done, std::size_t total) {
  if (!enabled_ || total == 0) return;
  const double seconds = monotonic_seconds() - start_seconds_;
  const double fraction = static_cast<double>(std::min(done, total)) / static_cast<double>(total);
  if (tty_) {
    if (done < total && seconds - last_draw_ < 0.1) return;
    last_draw_ = seconds;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::fprintf(stderr, "\r%s [%s%s] %3.0f%% %zu/%zu %s %.1f s", label_.c_str(),
                 std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(),
                 100 * fraction, done, total, unit_.c_str(), seconds);
    if (done >= total) std::fputc('\n', stderr);
  } else {
    const int decile = static_cast<int>(std::floor(fraction * 10));
    if (decile <= last_decile_) return;
    last_decile_ = decile;
    std::fprintf(stderr, "%s: %3d%% (%zu/%zu %s, %.1f s)\n", label_.c_str(), decile * 10, done,
                 total, unit_.c_str(), seconds);
  }
  std::fflush(stderr);
}

void print_warning(const std::string& message) {
  std::cerr << "rths: warning: " << message << "\n";
}

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
CLI::Validator range_validator(core::Quantity quantity, bool seconds) {
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
        const std::string violation = core::range_violation(quantity, value, "");
        if (!violation.empty()) return violation;
        if (seconds) {
          std::ostringstream out;
          out.precision(17);
          out << value;
          input = out.str();
        }
        return "";
      },
      core::range_of(quantity).text());
}
}  // namespace

CLI::Validator seconds_in(core::Quantity quantity) { return range_validator(quantity, true); }
CLI::Validator in_range(core::Quantity quantity) { return range_validator(quantity, false); }

std::optional<std::string> closest(const std::string& word,
                                   const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = std::max<std::size_t>(1, word.size() / 3) + 1;
  for (const std::string& candidate : candidates) {
    const std::size_t d = edit_distance(word, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

namespace {

std::vector<std::string> subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(sub->get_name());
  return names;
}

std::vector<std::string> flag_names(const CLI::App& app) {
  std::vector<std::string> flags;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) flags.push_back("--" + name);
  }
  return flags;
}

std::string unknown_command(const std::string& word, const std::string& path,
                            const std::vector<std::string>& names) {
  std::string message =
      "unknown command '" + word + "'" + (path == "rths" ? "" : " for `" + path + "`");
  if (const auto near = closest(word, names))
    return message + "; did you mean `" + path + " " + *near + "`?";
  message += "; commands:";
  for (const std::string& n : names) message += " " + n;
  return message;
}

std::string unknown_flag(const std::string& word, const std::string& path,
                         const std::vector<std::string>& flags) {
  std::string message = "unknown option '" + word + "' for `" + path + "`";
  if (const auto near = closest(word, flags)) return message + "; did you mean '" + *near + "'?";
  return message + " (see `" + path + " --help`)";
}

}  // namespace

std::string suggest_for_unknown(const CLI::App& app, int argc, const char* const* argv) {
  // Walks the words level by level: a subcommand name descends into it; a --flag is checked
  // against the flags of the level it appears at, so a nested command's slip is suggested from
  // its own flags; a bare word where a level needs a subcommand must be one of its names.
  const CLI::App* level = &app;
  std::string path = "rths";
  bool chose = false;
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    if (word == "--") break;
    if (word.rfind("--", 0) == 0) {
      if (level == &app) continue;  // --help, --version: CLI11's own
      word = word.substr(0, word.find('='));
      const std::vector<std::string> flags = flag_names(*level);
      if (std::find(flags.begin(), flags.end(), word) == flags.end())
        return unknown_flag(word, path, flags);
      continue;
    }
    if (word.empty() || word[0] == '-') continue;
    const std::vector<std::string> names = subcommand_names(*level);
    if (std::find(names.begin(), names.end(), word) != names.end()) {
      level = level->get_subcommand(word);
      path += " " + word;
      chose = false;
      continue;
    }
    const bool needs_subcommand = level->get_require_subcommand_min() > 0 && !chose;
    if (needs_subcommand && !names.empty()) return unknown_command(word, path, names);
    chose = true;
  }
  return "";
}

namespace {

// The study an output folder holds: its owner file's, else its summary.json's; empty for none.
std::string folder_owner(const std::filesystem::path& out) {
  std::ifstream owner(out / kOwnerFile);
  std::string name;
  if (owner && std::getline(owner, name)) return name;
  std::ifstream summary(out / "summary.json");
  if (!summary) return "";
  const nlohmann::json j = nlohmann::json::parse(summary, nullptr, false);
  return j.is_object() && j.contains("study") && j["study"].is_string()
             ? j["study"].get<std::string>()
             : "";
}

}  // namespace

void claim_output_folder(const std::filesystem::path& out, const std::string& study, bool force) {
  const std::string owner = folder_owner(out);
  if (!owner.empty() && owner != study && !force)
    throw ExitError(kExitBadInput, "output folder " + out.string() + " holds study '" + owner +
                                       "' (its " + kOwnerFile + "), not '" + study +
                                       "': give another --out, or --force to overwrite it");
  std::filesystem::create_directories(out);
  util::AtomicFile owner_file(out / kOwnerFile);
  owner_file.stream() << study << "\n";
  owner_file.commit();
}

void write_study_outputs(const analysis::StudyOutcome& outcome, const std::filesystem::path& out,
                         bool plots, bool json, const std::string& format) {
  std::filesystem::create_directories(out);
  const results::Format kind = results::parse_format(format);
  const std::filesystem::path results = out / ("results" + results::extension(kind));
  // Plots of an earlier run stay (they may be all a user has of it), named as such.
  std::string earlier_plots;
  if (!plots)
    for (const std::string& file : analysis::study_plot_files())
      if (std::filesystem::exists(out / file))
        earlier_plots += (earlier_plots.empty() ? "" : ", ") + file;
  // The figures are drawn (gnuplot processes, waited on by a thread) while this thread writes the
  // results table, so their time overlaps. A figure that fails costs only the figures: the table
  // and summary are written, the failure is a warning, and the exit stays the cases'.
  std::future<std::vector<std::string>> figures;
  if (plots)
    figures =
        std::async(std::launch::async, [&] { return analysis::write_study_plots(outcome, out); });
  try {
    results::write_table(analysis::study_table(outcome), results, kind);
  } catch (...) {
    if (figures.valid()) figures.wait();
    throw;
  }
  std::string drawn, failed;
  if (figures.valid()) try {
      for (const std::string& png : figures.get()) drawn += ", " + png + "/.svg";
    } catch (const std::runtime_error& e) {
      failed = e.what();
    }
  const nlohmann::json summary = analysis::study_summary_json(outcome);
  util::AtomicFile json_file(out / "summary.json");
  json_file.stream() << summary.dump(2) << "\n";
  json_file.commit();
  util::AtomicFile text_file(out / "summary.txt");
  text_file.stream() << analysis::study_summary_text(outcome);
  text_file.commit();
  if (json) {
    std::cout << summary.dump(2) << "\n";
  } else {
    std::cout << analysis::study_summary_text(outcome) << "written: " << results.string() << drawn
              << ", summary.txt, summary.json\n";
    if (!earlier_plots.empty())
      std::cout << "not redrawn (--no-plots), from an earlier run: " << earlier_plots << "\n";
  }
  if (!failed.empty())
    print_warning("no figure drawn (the table and summary are written): " + failed);
}

void write_benchmark_outputs(const core::PreparedStudy& prepared,
                             const analysis::StudyOutcome& outcome,
                             const std::filesystem::path& out, bool plots, bool quiet) {
  const auto benchmark = analysis::evaluate_benchmark(prepared, outcome);
  if (!benchmark) return;
  const std::string table = analysis::benchmark_table(*benchmark);
  util::AtomicFile text(out / "benchmark.txt");
  text.stream() << table;
  text.commit();
  util::AtomicFile json(out / "benchmark.json");
  json.stream() << analysis::benchmark_json(*benchmark).dump(2) << "\n";
  json.commit();
  std::string figures;
  if (plots) {
    try {
      for (const auto& png : analysis::write_benchmark_plots(*benchmark, outcome, out))
        figures += ", " + png.filename().string() + "/.svg";
    } catch (const std::runtime_error& e) {
      throw ExitError(
          kExitEnvironment,
          std::string("benchmark.txt and .json are written, the figures failed: ") + e.what());
    }
  }
  if (!quiet) std::cout << table << "written: benchmark.txt, benchmark.json" << figures << "\n";
}

void fail_if_unstable(const analysis::StudyOutcome& outcome, bool allow_unstable) {
  const std::vector<std::string> failures = outcome.failures(allow_unstable);
  if (failures.empty()) return;
  std::string message;
  bool diverged = false;
  for (const std::string& f : failures) {
    message += (message.empty() ? "" : "\n  ") + f;
    diverged = diverged || f.find("diverg") != std::string::npos;
  }
  if (diverged)
    message += "\n  (--allow-unstable, or expect_unstable: true in the case, when that is meant)";
  throw ExitError(kExitRunFailed, message);
}

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
