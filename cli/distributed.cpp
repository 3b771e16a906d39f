#include "cli/distributed.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "analysis/atomic_file.h"
#include "analysis/plot.h"
#include "cli/commands.h"
#include "cli/support.h"
#include "runtime/plan.h"
#include "runtime/record.h"
#include "runtime/schema.h"
#include "tables/results.h"
#include "tables/write.h"

namespace rths::cli {
namespace {

// Whether a lockstep run of this study reproduces core::simulate exactly (no node delay stages).
bool comparable_in_process(const config::Study& study) {
  if (study.deployment().clock() != config::Deployment::LOCKSTEP) return false;
  for (const auto& node : study.deployment().nodes()) {
    if (node.receive_delay_size() > 0 || node.send_delay_size() > 0) return false;
  }
  return true;
}

// max |u_distributed - u_in_process| over every floor and step; nullopt when the step counts differ.
std::optional<double> difference_from_in_process(const core::PreparedStudy& prepared,
                                                 const std::string& case_name,
                                                 const core::SimulationResult& recorded) {
  const core::HybridSetup setup =
      core::setup_for_case(prepared, runtime::find_case(prepared.config, case_name));
  const runtime::DeploymentPlan plan =
      runtime::make_plan(setup, runtime::with_default_nodes(prepared.config.deployment(), setup));
  const core::SimulationResult expected =
      core::simulate(runtime::with_node_compensation(setup, plan), prepared.motion);
  if (expected.displacement.rows() != recorded.displacement.rows() ||
      expected.displacement.cols() != recorded.displacement.cols())
    return std::nullopt;
  if (expected.displacement.size() == 0) return 0.0;
  return (expected.displacement - recorded.displacement).cwiseAbs().maxCoeff();
}

int exit_code_of(int coordinator_exit) {
  switch (coordinator_exit) {
    case 0: return kExitOk;
    case 1: return kExitRunFailed;
    case 2: return kExitBadInput;
    default: return kExitEnvironment;
  }
}

std::vector<std::string> lag_plot_files(const DistributedResults& results) {
  std::vector<std::string> files;
  for (const auto& c : results.outcome.cases)
    for (const char* extension : {".png", ".svg"}) files.push_back("lag_" + c.name + extension);
  return files;
}

}  // namespace

DistributedResults judge_distributed(const core::PreparedStudy& prepared,
                                     const std::vector<DistributedRun>& runs) {
  DistributedResults results;
  std::vector<analysis::RecordedCase> recorded;
  const bool comparable = comparable_in_process(prepared.config);
  const config::Deployment deployment =
      runtime::with_default_nodes(prepared.config.deployment(), prepared.base);
  for (const DistributedRun& run : runs) {
    if (!std::filesystem::exists(run.record)) {
      results.missing.emplace_back(run.case_name, run.launcher_status.empty()
                                                      ? "no record written; see " + run.log_hint
                                                      : run.launcher_status + "; see " + run.log_hint);
      continue;
    }
    const runtime::RecordContents record = runtime::read_record(run.record);
    if (record.truncated) print_warning(record.warning);
    if (record.header() == nullptr) {
      results.missing.emplace_back(run.case_name, "the record has no header; see " + run.log_hint);
      continue;
    }
    runtime::RunMeasurements measured = runtime::measure_run(record);
    analysis::RecordedCase c;
    c.name = run.case_name;
    DistributedCaseFacts facts;
    facts.coordinator_exit = run.coordinator_exit;
    facts.record = run.record;
    if (measured.has_footer) {
      c.status = measured.footer.status();
      const auto& k = measured.footer.counters();
      facts.overruns = k.overruns();
      facts.rejected = k.foreign_run() + k.garbage() + k.duplicate() + k.stale() + k.out_of_order() +
                       k.unknown_node();
    } else {
      c.status = "cut short";
      c.status_detail = "the record has no footer: the coordinator stopped abruptly";
    }
    if (!run.launcher_status.empty()) {
      c.status = run.launcher_status;
      c.status_detail = run.launcher_status + "; see " + run.log_hint;
    }
    for (const config::NodeSpec& node : deployment.nodes())
      facts.link_labels[node.id()] =
          "node " + std::to_string(node.id()) + " (" + runtime::node_kind_name(node.kind()) + ")";
    if (comparable && run.coordinator_exit == 0)
      facts.max_difference_from_in_process =
          difference_from_in_process(prepared, run.case_name, measured.steps);
    c.simulation = std::move(measured.steps);
    results.links.push_back(std::move(measured.links));
    results.facts.push_back(std::move(facts));
    recorded.push_back(std::move(c));
  }
  if (!recorded.empty())
    results.outcome = analysis::judge_recorded_cases(prepared, std::move(recorded), {.warn = print_warning});
  return results;
}

std::filesystem::path write_distributed_outputs(const DistributedResults& results,
                                                const std::filesystem::path& out, bool plots,
                                                const std::string& format) {
  std::filesystem::create_directories(out);
  const tables::Format kind = tables::parse_format(format);
  const std::filesystem::path table_file = out / ("results" + tables::extension(kind));
  if (!results.outcome.cases.empty())
    tables::write_table(tables::distributed_study_table(results.outcome, results.links), table_file, kind);
  if (!plots) {
    // A folder must not show plots of an earlier run beside this run's results.
    for (const std::string& file : analysis::study_plot_files()) std::filesystem::remove(out / file);
    for (const std::string& file : lag_plot_files(results)) std::filesystem::remove(out / file);
  } else if (!results.outcome.cases.empty()) {
    try {
      analysis::write_study_plots(results.outcome, out);
      for (std::size_t i = 0; i < results.outcome.cases.size(); ++i) {
        const auto& c = results.outcome.cases[i];
        analysis::PlotSpec lag{"lag per link, case " + c.name, "time (s)", "lag (ms)", {}};
        for (const auto& [node, series] : results.links[i]) {
          const auto label = results.facts[i].link_labels.count(node)
                                 ? results.facts[i].link_labels.at(node)
                                 : "node " + std::to_string(node);
          std::vector<double> rtt_ms, inj_ms;
          for (double x : series.round_trip) rtt_ms.push_back(x * 1e3);
          for (double x : series.injected) inj_ms.push_back(x * 1e3);
          lag.series.push_back({label + ": measured round trip", series.time, rtt_ms, "lines"});
          lag.series.push_back({label + ": injected", series.time, inj_ms, "lines"});
        }
        if (!lag.series.empty()) analysis::write_png_plot(lag, out / ("lag_" + c.name + ".png"));
      }
    } catch (const std::exception& e) {
      print_warning(std::string("plots not written: ") + e.what());
    }
  }
  analysis::AtomicFile json_file(out / "summary.json");
  json_file.stream() << distributed_summary_json(results).dump(2) << "\n";
  json_file.commit();
  analysis::AtomicFile text_file(out / "summary.txt");
  text_file.stream() << distributed_summary_text(results);
  text_file.commit();
  return table_file;
}

std::string distributed_summary_text(const DistributedResults& results) {
  std::ostringstream text;
  if (!results.outcome.cases.empty()) text << analysis::study_summary_text(results.outcome);
  text << std::fixed << std::setprecision(3);
  for (std::size_t i = 0; i < results.outcome.cases.size(); ++i) {
    const auto& c = results.outcome.cases[i];
    const auto& f = results.facts[i];
    text << c.name << ": " << c.simulation.steps() << " steps, coordinator exit " << f.coordinator_exit
         << ", overruns " << f.overruns << ", rejected " << f.rejected << ", record " << f.record.string()
         << "\n";
    if (f.max_difference_from_in_process) {
      if (*f.max_difference_from_in_process == 0.0)
        text << "  equals the in-process run of the same case bit for bit\n";
      else
        text << "  DIFFERS from the in-process run of the same case: max |du| = " << std::scientific
             << *f.max_difference_from_in_process << std::fixed << " m\n";
    }
    for (const auto& [node, series] : results.links[i]) {
      const auto rt = series.round_trip_summary();
      const auto inj = series.injected_summary();
      text << "  " << (f.link_labels.count(node) ? f.link_labels.at(node) : "node " + std::to_string(node))
           << " round trip ms: median " << rt.median * 1e3 << ", p99 " << rt.p99 * 1e3 << ", max "
           << rt.max * 1e3 << " (injected median " << inj.median * 1e3 << ", " << rt.count
           << " answers)\n";
    }
  }
  for (const auto& [name, why] : results.missing) text << name << ": FAILED, " << why << "\n";
  return text.str();
}

nlohmann::json distributed_summary_json(const DistributedResults& results) {
  nlohmann::json j = results.outcome.cases.empty()
                         ? nlohmann::json{{"reference", analysis::kLagFreeReference},
                                          {"cases", nlohmann::json::array()}}
                         : analysis::study_summary_json(results.outcome);
  for (std::size_t i = 0; i < results.outcome.cases.size(); ++i) {
    const auto& f = results.facts[i];
    nlohmann::json links = nlohmann::json::object();
    for (const auto& [node, series] : results.links[i]) {
      const auto rt = series.round_trip_summary();
      const auto inj = series.injected_summary();
      links[std::to_string(node)] = {{"label", f.link_labels.count(node) ? f.link_labels.at(node) : ""},
                                     {"answers", rt.count},
                                     {"round_trip_median_s", rt.median},
                                     {"round_trip_p99_s", rt.p99},
                                     {"round_trip_max_s", rt.max},
                                     {"injected_median_s", inj.median}};
    }
    auto& c = j["cases"][i];
    c["coordinator_exit"] = f.coordinator_exit;
    c["overruns"] = f.overruns;
    c["rejected"] = f.rejected;
    c["links"] = links;
    c["record"] = f.record.string();
    c["max_difference_from_in_process_m"] = f.max_difference_from_in_process
                                                ? nlohmann::json(*f.max_difference_from_in_process)
                                                : nlohmann::json();
  }
  nlohmann::json missing = nlohmann::json::array();
  for (const auto& [name, why] : results.missing) missing.push_back({{"case", name}, {"why", why}});
  j["failed_without_record"] = missing;
  return j;
}

void fail_if_distributed_failed(const DistributedResults& results,
                                const std::vector<DistributedRun>& runs, bool allow_unstable) {
  for (const DistributedRun& run : runs) {
    if (run.coordinator_exit != 0) {
      std::string status = run.launcher_status;
      for (std::size_t i = 0; i < results.outcome.cases.size(); ++i)
        if (results.outcome.cases[i].name == run.case_name && status.empty())
          status = results.outcome.cases[i].status;
      throw ExitError(exit_code_of(run.coordinator_exit),
                      "case " + run.case_name + ": " + status + "; see " + run.log_hint);
    }
  }
  if (!results.missing.empty())
    throw ExitError(kExitEnvironment, "case " + results.missing.front().first + ": " +
                                          results.missing.front().second);
  fail_if_unstable(results.outcome, allow_unstable);
}

}  // namespace rths::cli
