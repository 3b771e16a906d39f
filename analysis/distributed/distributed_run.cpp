#include "analysis/distributed/distributed_run.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "core/time_text.h"
#include "runtime/node/in_process.h"
#include "runtime/node/plan.h"
#include "runtime/node/schema.h"
#include "runtime/node/validation.h"
#include "runtime/record/deadline_diagnosis.h"
#include "runtime/record/node_health.h"
#include "runtime/record/record.h"

namespace rths::analysis {
namespace {

// Whether a lockstep run of this study reproduces core::simulate exactly (no node delay stages).
bool comparable_in_process(const config::Study& study) {
  if (study.deployment().clock() != config::Deployment::LOCKSTEP) return false;
  for (const auto& node : study.deployment().nodes()) {
    if (node.receive_delay_size() > 0 || node.send_delay_size() > 0) return false;
  }
  return true;
}

// max |u_distributed - u_in_process| over every recorded floor and step, and the first step where
// they differ; nullopt when the step counts differ.
std::optional<InProcessDifference> difference_from_in_process(
    const study::PreparedStudy& prepared, const std::string& case_name,
    const core::SimulationResult& recorded) {
  const core::SimulationResult expected = core::simulate(
      runtime::in_process_setup(prepared, study::find_case(prepared.config, case_name)),
      prepared.motion,
      study::kept_by_recorders(prepared.recorders, prepared.config.deployment().limits()));
  if (expected.displacement.rows() != recorded.displacement.rows() ||
      expected.displacement.cols() != recorded.displacement.cols())
    return std::nullopt;
  InProcessDifference difference;
  if (expected.displacement.size() == 0) return difference;
  const core::Mat delta = (expected.displacement - recorded.displacement).cwiseAbs();
  difference.max = delta.maxCoeff();
  std::tie(difference.tolerance, difference.resolution) = frame_rounding_tolerance(
      prepared.config.deployment(), expected.displacement.cwiseAbs().maxCoeff());
  for (Eigen::Index k = 0; k < delta.rows() && !difference.first_step; ++k)
    if (delta.row(k).maxCoeff() != 0.0) difference.first_step = static_cast<std::int64_t>(k);
  return difference;
}

}  // namespace

std::pair<double, std::string> frame_rounding_tolerance(const config::Deployment& deployment,
                                                        double peak_displacement) {
  double relative = 0.0;
  std::string kind;
  for (const auto& node : deployment.nodes()) {
    if (!node.has_controller()) continue;
    for (const auto* layout : {&node.controller().command(), &node.controller().feedback()})
      for (const config::FrameField& f : layout->fields()) {
        if (f.role() != config::FrameField::TARGET_DISPLACEMENT &&
            f.role() != config::FrameField::MEASURED_DISPLACEMENT &&
            f.role() != config::FrameField::MEASURED_FORCE)
          continue;
        const bool scaled = f.scale() != 0.0 && f.scale() != 1.0;
        double r = 0.0;
        std::string k;
        if (f.type() == config::FrameField::F32) {
          r = 1e-5, k = "f32 fields: 1e-5 x peak |u|";
        } else if (f.type() == config::FrameField::I32 || f.type() == config::FrameField::U32) {
          r = 1e-3, k = "integer fields: 1e-3 x peak |u|";
        } else if (scaled) {
          r = 1e-12, k = "scaled f64 fields: 1e-12 x peak |u|";
        }
        if (r > relative) relative = r, kind = k;
      }
  }
  if (relative == 0.0) return {0.0, ""};
  return {relative * peak_displacement, kind};
}

namespace {

// A node's rejects by cause, with what its transport dropped unread for want of a MAC (never
// seen by its checks, so not in `rejected`'s total).
nlohmann::json rejects_json(const runtime::Counters& c) {
  return {{"foreign_run", c.foreign_run()},
          {"garbage", c.garbage()},
          {"duplicate", c.duplicate()},
          {"stale", c.stale()},
          {"out_of_order", c.out_of_order()},
          {"unknown_node", c.unknown_node()},
          {"not_entitled", c.not_entitled()},
          {"out_of_range", c.out_of_range()},
          {"unauthenticated", c.unauthenticated()}};
}

std::string rejects_text(const runtime::Counters& c) {
  std::string text;
  const nlohmann::json causes = rejects_json(c);
  for (const auto& cause : causes.items()) {
    const auto n = cause.value().get<std::uint64_t>();
    if (n > 0) text += (text.empty() ? "" : ", ") + cause.key() + " " + std::to_string(n);
  }
  return text.empty() ? "none" : text;
}

}  // namespace

StepTiming step_timing(const runtime::RecordContents& record) {
  std::vector<double> work;
  const runtime::StepRecord* first = nullptr;
  for (const runtime::StepRecord* s : record.steps()) {
    if (s->step() < 1) continue;
    work.push_back(s->step_wall());
    if (!first) first = s;
  }
  StepTiming timing;
  const runtime::LagSummary summary = runtime::summarize(std::move(work));
  timing.work_median = summary.median;
  timing.work_p99 = summary.p99;
  const runtime::RunHeader* header = record.header();
  if (header && first && header->start_realtime_ns() > 0 && first->start_realtime_ns() > 0)
    timing.start_to_step1 =
        1e-9 * static_cast<double>(first->start_realtime_ns() - header->start_realtime_ns());
  return timing;
}

ActuatorPathLag actuator_path_lag(const study::PreparedStudy& prepared) {
  const config::Deployment deployment =
      runtime::with_default_nodes(prepared.config.deployment(), prepared.base);
  ActuatorPathLag worst;
  worst.real_time = deployment.clock() == config::Deployment::REAL_TIME;
  for (const config::NodeSpec& node : deployment.nodes()) {
    if (!runtime::drives_actuators(node.kind())) continue;
    ActuatorPathLag lag;
    lag.node_id = node.id();
    lag.real_time = worst.real_time;
    lag.link_round_trip = node.receive_lag().one_way_delay() + node.send_lag().one_way_delay();
    for (const auto* stages : {&node.receive_delay(), &node.send_delay()})
      if (!stages->empty())
        lag.node_stages +=
            study::make_delay_chain(*stages, prepared.base.dt, prepared.base_dir).nominal_delay();
    if (worst.node_id < 0 || lag.felt() > worst.felt()) worst = lag;
  }
  return worst;
}

int warn_past_critical_delay(const study::PreparedStudy& prepared,
                             const std::vector<std::string>& case_names,
                             const std::function<void(const std::string&)>& warn) {
  const ActuatorPathLag path = actuator_path_lag(prepared);
  int past = 0;
  for (const std::string& name : case_names) {
    const config::Case& study_case = study::find_case(prepared.config, name);
    // A force predictor leaves only its model's error to the lag: its own verdict decides.
    if (const auto predicted =
            analysis::predicted_loop_verdict(prepared, study_case, path.felt())) {
      if (predicted->analysed && !predicted->stable) {
        ++past;
        warn("case '" + study_case.name() + "': " + predicted->text +
             (study_case.expect_unstable() ? " (expect_unstable: meant)"
                                           : "; expect it to diverge"));
      } else if (predicted->relies_on_fit) {
        warn("case '" + study_case.name() + "': " + predicted->text);
      }
      continue;
    }
    const auto check = analysis::check_case_critical_delay(prepared, study_case, path.felt());
    if (!check || !check->past()) continue;
    ++past;
    std::string parts;
    if (path.real_time && path.link_round_trip != 0.0)
      parts += "network round trip " + core::format_ms(path.link_round_trip) +
               " injected on the actuator lab's link + ";
    if (path.node_stages != 0.0)
      parts += "the actuator node's delay stages " + core::format_ms(path.node_stages) + " + ";
    parts += "actuator lag " + core::format_ms(check->lag - path.felt()) +
             " (the case's delay stages): ";
    if (!path.real_time && path.link_round_trip != 0.0)
      parts = "(lockstep: the link's " + core::format_ms(path.link_round_trip) +
              " round trip does not enter) " + parts;
    warn("case '" + study_case.name() + "': " + parts + check->describe() +
         (study_case.expect_unstable() ? " (expect_unstable: meant)" : "; expect it to diverge"));
  }
  return past;
}

std::map<int, std::string> link_roles(const config::Deployment& deployment,
                                      const std::map<int, std::string>& site_of_node) {
  std::map<int, int> sharing;  // kind -> nodes of that kind
  for (const config::NodeSpec& node : deployment.nodes()) ++sharing[node.kind()];
  std::map<int, std::string> labels;
  for (const config::NodeSpec& node : deployment.nodes()) {
    std::string label = node.kind() == config::NodeSpec::CONTROLLER          ? "controller"
                        : node.kind() == config::NodeSpec::ACTUATOR_EMULATOR ? "actuator lab"
                        : node.kind() == config::NodeSpec::SUBSTRUCTURE      ? "numerical site"
                                                                             : "node";
    const auto site = site_of_node.find(node.id());
    if (site != site_of_node.end() && !site->second.empty())
      label += " \"" + site->second + "\"";
    else if (sharing[node.kind()] > 1)
      label += " (node " + std::to_string(node.id()) + ")";
    labels[node.id()] = label;
  }
  return labels;
}

namespace {

// The case's status from the record's footer, overruled by a damaged record, then by the
// launcher's word; the footer's counters go to the facts.
void judge_status(const DistributedRun& run, const runtime::RecordContents& record,
                  const runtime::RunMeasurements& measured, analysis::RecordedCase& c,
                  DistributedCaseFacts& facts) {
  if (measured.has_footer) {
    c.status = measured.footer.status();
    const auto& k = measured.footer.counters();
    facts.overruns = k.overruns();
    facts.rejected = runtime::RejectCounters::from(k).total();
    facts.unauthenticated = k.unauthenticated();
    facts.node_rejects.assign(measured.footer.node_rejects().begin(),
                              measured.footer.node_rejects().end());
    // Under the record's own deployment, the one the coordinator judged the run by.
    if (runtime::needs_deadline_diagnosis(c.status, k.overruns()))
      if (const auto d = runtime::diagnose_record_deadlines(record))
        facts.deadline_diagnosis = d->describe();
  } else {
    c.status = "cut short";
    c.status_detail = "the record has no footer: the coordinator stopped abruptly";
  }
  if (record.lost_entries()) {  // checksums failed: its rows are not the run's
    c.status = "record damaged";
    c.status_detail = record.loss_report();
  }
  if (!run.launcher_status.empty()) {
    c.status = run.launcher_status;
    c.status_detail = run.launcher_status + "; see " + run.log_hint;
  }
}

// The counts behind a link's round trip: the answers it was measured on (each once, at the first
// step that applied it), the answers the coordinator accepted (superseded ones included: a step
// applies only the newest) and the steps, so "3369 answers" over 10,000 steps reads as what it
// is. A record without the accepted count (an older one) gives the first and the last.
std::string answer_counts(std::size_t measured, const runtime::LinkSeries& series,
                          std::size_t steps) {
  const std::int64_t accepted = series.answers.empty() ? 0 : series.answers.back();
  std::ostringstream text;
  text << "measured on " << measured << " answers, each at the first step that applied it";
  if (accepted > 0) text << ", of " << accepted << " accepted";
  if (accepted > static_cast<std::int64_t>(measured))
    text << " (a step applies only the newest: " << accepted - static_cast<std::int64_t>(measured)
         << " arrived behind a newer one)";
  text << ", over " << steps << " steps";
  return text.str();
}

}  // namespace

DistributedResults judge_distributed(const study::PreparedStudy& prepared,
                                     const std::vector<DistributedRun>& runs,
                                     const std::function<void(const std::string&)>& warn,
                                     const std::map<int, std::string>& site_of_node) {
  DistributedResults results;
  results.actuator_path = actuator_path_lag(prepared);
  const std::map<int, std::string> roles = link_roles(
      runtime::with_default_nodes(prepared.config.deployment(), prepared.base), site_of_node);
  std::vector<analysis::RecordedCase> recorded;
  const bool comparable = comparable_in_process(prepared.config);
  for (const DistributedRun& run : runs) {
    if (!std::filesystem::exists(run.record)) {
      results.missing.emplace_back(run.case_name,
                                   run.launcher_status.empty()
                                       ? "no record written; see " + run.log_hint
                                       : run.launcher_status + "; see " + run.log_hint);
      continue;
    }
    const runtime::RecordContents record = runtime::read_record(run.record);
    if (!record.warning.empty()) warn(record.warning);
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
    if (measured.steps.steps() < 2) {
      // Stopped before step 1, or a record cut before its first step (a full disk, a file size
      // limit): nothing to compare; the footer, or the launcher and the reader, say why.
      const std::string why =
          measured.has_footer
              ? measured.footer.status()
              : (run.launcher_status.empty() ? "" : run.launcher_status + "; ") +
                    (record.warning.empty() ? "the record has no footer" : record.warning);
      results.missing.emplace_back(run.case_name,
                                   "stopped before step 1: " + why + "; see " + run.log_hint);
      continue;
    }
    judge_status(run, record, measured, c, facts);
    facts.timing = step_timing(record);
    facts.link_labels = roles;
    if (comparable && run.coordinator_exit == 0)
      facts.difference_from_in_process =
          difference_from_in_process(prepared, run.case_name, measured.steps);
    c.simulation = std::move(measured.steps);
    results.links.push_back(std::move(measured.links));
    results.facts.push_back(std::move(facts));
    recorded.push_back(std::move(c));
  }
  if (!recorded.empty())
    // Warned before the runs (warn_past_critical_delay); the outcome keeps the same check.
    results.outcome = analysis::judge_recorded_cases(
        prepared, std::move(recorded), {.warn = {}, .extra_lag = results.actuator_path.felt()});
  return results;
}

std::string distributed_summary_text(const DistributedResults& results) {
  std::ostringstream text;
  if (!results.outcome.cases.empty()) text << analysis::study_summary_text(results.outcome);
  text << std::fixed << std::setprecision(3);
  for (std::size_t i = 0; i < results.outcome.cases.size(); ++i) {
    const auto& c = results.outcome.cases[i];
    const auto& f = results.facts[i];
    text << c.name << ": " << c.simulation.steps() << " steps, coordinator exit "
         << f.coordinator_exit << ", overruns " << f.overruns << ", rejected " << f.rejected
         << (f.unauthenticated ? ", unauthenticated " + std::to_string(f.unauthenticated) : "")
         << ", record " << f.record.string() << "\n";
    text << "  step work median " << f.timing.work_median * 1e3 << " ms, p99 "
         << f.timing.work_p99 * 1e3 << " ms (a step's exchange and integration; the step is "
         << c.simulation.dt * 1e3 << " ms); step 1 began " << f.timing.start_to_step1
         << " s after the coordinator started up (the nodes' start-up, the loop's set-up)\n";
    if (!f.deadline_diagnosis.empty()) text << "  " << f.deadline_diagnosis;
    if (f.difference_from_in_process) {
      const InProcessDifference& d = *f.difference_from_in_process;
      if (!d.first_step)
        text << "  equals the in-process run of the same case bit for bit\n";
      else if (!d.differs())
        text << "  equals the in-process run of the same case within the controller frames' "
                "resolution ("
             << d.resolution << ": max |du| = " << std::scientific << d.max << " m, allowed "
             << d.tolerance << std::fixed << " m)\n";
      else
        text << "  DIFFERS from the in-process run of the same case from step "
             << *f.difference_from_in_process->first_step << ": max |du| = " << std::scientific
             << f.difference_from_in_process->max << std::fixed << " m\n";
    }
    for (const runtime::NodeRejects& n : f.node_rejects) {
      text << "  " << n.label() << " DDS messages rejected: " << rejects_text(n.rejected())
           << (n.final() ? "" : " (as of its last heartbeat)") << "\n";
      for (const std::string& line :
           {runtime::controller_link_text(n), runtime::answer_age_text(n)})
        if (!line.empty()) text << "  " << line;
    }
    for (const auto& [node, series] : results.links[i]) {
      const auto rt = series.round_trip_summary();
      const auto inj = series.injected_summary();
      text << "  "
           << (f.link_labels.count(node) ? f.link_labels.at(node) : "node " + std::to_string(node))
           << " DDS round trip ms (coordinator <-> node): median " << rt.median * 1e3 << ", p99 "
           << rt.p99 * 1e3 << ", max " << rt.max * 1e3 << " (injected median " << inj.median * 1e3
           << "; " << answer_counts(rt.count, series, results.outcome.cases[i].simulation.steps())
           << ")\n";
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
      links[std::to_string(node)] = {
          {"label", f.link_labels.count(node) ? f.link_labels.at(node) : ""},
          {"answers", rt.count},
          {"round_trip_median_s", rt.median},
          {"round_trip_p99_s", rt.p99},
          {"round_trip_max_s", rt.max},
          {"injected_median_s", inj.median}};
    }
    auto& c = j["cases"][i];
    c["coordinator_exit"] = f.coordinator_exit;
    c["overruns"] = f.overruns;
    c["step_work_median_s"] = f.timing.work_median;
    c["step_work_p99_s"] = f.timing.work_p99;
    c["start_to_step1_s"] = f.timing.start_to_step1;
    c["rejected"] = f.rejected;
    c["unauthenticated"] = f.unauthenticated;
    c["links"] = links;
    c["record"] = f.record.string();
    c["deadline_diagnosis"] =
        f.deadline_diagnosis.empty() ? nlohmann::json() : nlohmann::json(f.deadline_diagnosis);
    c["max_difference_from_in_process_m"] = f.difference_from_in_process
                                                ? nlohmann::json(f.difference_from_in_process->max)
                                                : nlohmann::json();
    c["in_process_tolerance_m"] = f.difference_from_in_process
                                      ? nlohmann::json(f.difference_from_in_process->tolerance)
                                      : nlohmann::json();
    c["first_step_differing_from_in_process"] =
        f.difference_from_in_process && f.difference_from_in_process->first_step
            ? nlohmann::json(*f.difference_from_in_process->first_step)
            : nlohmann::json();
    nlohmann::json nodes = nlohmann::json::array();
    for (const runtime::NodeRejects& n : f.node_rejects)
      nodes.push_back({{"node_id", n.node_id()},
                       {"label", n.label()},
                       {"final", n.final()},
                       {"rejected", rejects_json(n.rejected())},
                       {"health", runtime::node_health_json(n)}});
    c["node_rejects"] = nodes;
  }
  nlohmann::json missing = nlohmann::json::array();
  for (const auto& [name, why] : results.missing) missing.push_back({{"case", name}, {"why", why}});
  j["failed_without_record"] = missing;
  return j;
}

}  // namespace rths::analysis
