#include "cli/study_outputs.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <future>
#include <iostream>

#include "analysis/benchmark/benchmark_evaluation.h"
#include "analysis/benchmark/benchmark_plots.h"
#include "analysis/study_run/response_envelope_plots.h"
#include "analysis/tables/result_tables.h"
#include "cli/commands.h"
#include "cli/console.h"
#include "results/results.h"
#include "results/write.h"
#include "util/atomic_file.h"

namespace rths::cli {

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
    for (const std::string& file : analysis::study_plot_files(out))
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

void write_benchmark_outputs(const study::PreparedStudy& prepared,
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

}  // namespace rths::cli
