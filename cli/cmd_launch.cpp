// rths launch CONFIG: run a study's cases distributed on this machine (coordinator, substructure
// node and actuator emulator as separate processes over Cyclone DDS on loopback), one run per
// case, then write per case the run record, CSV, logs, and plots of the response and of the
// injected vs measured lag, and print a summary (peaks, NRMSE vs the reference case, measured
// round trips, overruns, rejected messages).
// Exit: 0 all runs completed; else the first failing coordinator's status (1 run failed,
// 2 bad config, 3 environment); 2 for a bad config caught before starting anything.
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <map>

#include "analysis/plot.h"
#include "cli/commands.h"
#include "core/metrics.h"
#include "core/simulation.h"
#include "core/study.h"
#include "runtime/lag.h"
#include "runtime/launch.h"
#include "runtime/measurements.h"
#include "runtime/record.h"
#include "tables/results.h"
#include "tables/write.h"
#include "transport/transport.h"

namespace rths::cli {
namespace {

struct LaunchArgs {
  std::string config, out, bin_dir, security;
  std::vector<std::string> cases;
  int domain = -1;
  double timeout = 0;
  std::string cpu_placement = "auto";
  std::string format = "csv";  // of each case's results table: csv | mat | h5
  bool no_plots = false, json = false;
};

struct CaseOutcome {
  std::string name;
  int exit_code = -1;
  std::string status;
  std::vector<double> time, u1;  // s, m (DOF 1)
  std::map<int, std::vector<double>> round_trip, injected, step_time;  // per node id
  std::uint64_t overruns = 0, rejected = 0, steps = 0;
  double peak = 0, nrmse = -1;
  // Lockstep without node-level delay stages must equal core::simulate of the same case bit for
  // bit; -1 when that comparison does not apply (real time, node delay stages, failed run).
  double max_difference_from_in_process = -1;
  std::filesystem::path record, csv;
};

// Whether a lockstep run of this study is expected to reproduce core::simulate exactly.
bool comparable_in_process(const config::Study& study) {
  if (study.deployment().clock() != config::Deployment::LOCKSTEP) return false;
  for (const auto& node : study.deployment().nodes()) {
    if (!node.receive_delay_case().empty() || !node.send_delay_case().empty()) return false;
  }
  return true;
}

// max |u1_distributed - u1_in_process| over the run; u1 is floor 1, as in the record.
double difference_from_in_process(const core::PreparedStudy& prepared, const std::string& case_name,
                                  const std::vector<double>& u1) {
  for (const config::Case& c : prepared.config.cases()) {
    if (c.name() != case_name) continue;
    const core::SimulationResult expected = core::simulate(core::setup_for_case(prepared, c), prepared.motion);
    if (static_cast<std::size_t>(expected.displacement.rows()) != u1.size()) return -1;
    double worst = 0;
    for (std::size_t k = 0; k < u1.size(); ++k) {
      worst = std::max(worst, std::abs(u1[k] - expected.displacement(static_cast<Eigen::Index>(k), 0)));
    }
    return worst;
  }
  return -1;
}

void collect(const runtime::RecordContents& record, CaseOutcome& c) {
  const runtime::RunMeasurements m = runtime::measure_run(record);
  c.time = m.steps.time;
  c.u1.resize(c.time.size());
  for (std::size_t k = 0; k < c.u1.size() && m.steps.displacement.cols() > 0; ++k)
    c.u1[k] = m.steps.displacement(static_cast<Eigen::Index>(k), 0);
  for (const auto& [node, series] : m.links) {
    c.round_trip[node] = series.round_trip;
    c.injected[node] = series.injected;
    c.step_time[node] = series.time;
  }
  c.peak = c.u1.empty() ? 0.0 : core::peak_abs(c.u1);
  if (const auto* f = record.footer()) {
    c.status = f->status();
    const auto& k = f->counters();
    c.overruns = k.overruns();
    c.steps = k.steps();
    c.rejected = k.foreign_run() + k.garbage() + k.duplicate() + k.stale() + k.out_of_order() +
                 k.unknown_node();
  } else {
    c.status = "record without footer: the coordinator died";
  }
}

void plot(const std::filesystem::path& out, const std::vector<CaseOutcome>& cases) {
  analysis::PlotSpec response{"Floor 1 displacement, distributed runs", "time (s)",
                              "displacement (m)", {}};
  for (const auto& c : cases) response.series.push_back({c.name, c.time, c.u1});
  analysis::write_png_plot(response, out / "displacement.png");
  for (const auto& c : cases) {
    analysis::PlotSpec lag{"Lag per link, case " + c.name, "time (s)", "lag (ms)", {}};
    for (const auto& [node, rtt] : c.round_trip) {
      std::vector<double> rtt_ms, inj_ms;
      for (double x : rtt) rtt_ms.push_back(x * 1e3);
      for (double x : c.injected.at(node)) inj_ms.push_back(x * 1e3);
      lag.series.push_back({"node " + std::to_string(node) + " measured round trip",
                            c.step_time.at(node), rtt_ms, "lines"});
      lag.series.push_back({"node " + std::to_string(node) + " injected",
                            c.step_time.at(node), inj_ms, "lines"});
    }
    if (!lag.series.empty()) analysis::write_png_plot(lag, out / ("lag_" + c.name + ".png"));
  }
}

int exit_code_of(int coordinator_exit) {
  switch (coordinator_exit) {
    case 0: return kExitOk;
    case 1: return kExitRunFailed;
    case 2: return kExitBadInput;
    default: return kExitEnvironment;
  }
}

void run_launch(const LaunchArgs& args) {
  config::Study study;
  try {
    study = core::load_study(args.config);
  } catch (const std::exception& e) {
    throw ExitError(kExitBadInput, e.what());
  }
  std::vector<std::string> names = args.cases;
  if (names.empty())
    for (const auto& c : study.cases()) names.push_back(c.name());
  const std::string reference = core::reference_case(study).name();
  const std::filesystem::path out =
      !args.out.empty() ? std::filesystem::path(args.out)
      : !study.output().directory().empty()
          ? std::filesystem::path(study.output().directory()) / "distributed"
          : std::filesystem::path("rths_launch_" + study.name());
  std::filesystem::create_directories(out);
  runtime::ensure_dds_config();

  std::vector<CaseOutcome> outcomes;
  const std::string stamp = std::to_string(transport::realtime_ns());
  for (const std::string& name : names) {
    CaseOutcome c;
    c.name = name;
    runtime::LaunchOptions options;
    options.config = args.config;
    options.case_name = name;
    options.run_id = study.name() + "-" + name + "-" + stamp;
    options.domain = args.domain;
    options.programs_dir = args.bin_dir;
    options.record = c.record = out / (name + ".rthsrec");
    options.log_dir = out / "logs" / name;
    options.timeout = args.timeout;
    options.security_dir = args.security;
    options.cpu_placement = args.cpu_placement == "one-cpu" ? runtime::CpuPlacement::kOneCpu
                            : args.cpu_placement == "spread" ? runtime::CpuPlacement::kSpread
                                                             : runtime::CpuPlacement::kAuto;
    if (!args.json) std::cerr << "rths launch: case " << name << " ...\n";
    runtime::LaunchResult result;
    try {
      result = runtime::launch_run(options);
    } catch (const std::invalid_argument& e) {
      throw ExitError(kExitBadInput, e.what());
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, e.what());
    }
    c.exit_code = result.coordinator_exit;
    if (std::filesystem::exists(c.record)) {
      const auto record = runtime::read_record(c.record);
      if (record.truncated) std::cerr << "rths launch: warning: " << record.warning << "\n";
      collect(record, c);
      const tables::Format format = tables::parse_format(args.format);
      c.csv = out / (name + tables::extension(format));
      if (record.header()) tables::write_table(tables::record_table(record), c.csv, format);
    } else {
      c.status = "no record written; see " + result.coordinator_log.string();
    }
    if (c.exit_code != 0)
      std::cerr << "rths launch: case " << name << " failed (exit " << c.exit_code << "): "
                << c.status << "; logs in " << options.log_dir << "\n";
    outcomes.push_back(std::move(c));
  }
  const CaseOutcome* ref = nullptr;
  for (const auto& c : outcomes)
    if (c.name == reference) ref = &c;
  for (auto& c : outcomes)
    if (ref && ref != &c && ref->u1.size() == c.u1.size() && !c.u1.empty())
      c.nrmse = core::nrmse(ref->u1, c.u1);
  if (comparable_in_process(study)) {
    const auto prepared = core::prepare_study(study, std::filesystem::path(args.config).parent_path());
    for (auto& c : outcomes)
      if (c.exit_code == 0) c.max_difference_from_in_process = difference_from_in_process(prepared, c.name, c.u1);
  }
  if (!args.no_plots) {
    try {
      plot(out, outcomes);
    } catch (const std::exception& e) {
      std::cerr << "rths launch: warning: plots not written: " << e.what() << "\n";
    }
  }

  nlohmann::json j = nlohmann::json::array();
  std::ostringstream text;
  text << std::fixed << std::setprecision(3);
  for (const auto& c : outcomes) {
    nlohmann::json links = nlohmann::json::object();
    text << c.name << ": " << c.status << ", " << c.steps << " steps, peak |u1| " << c.peak * 1e3
         << " mm";
    if (c.nrmse >= 0) text << ", NRMSE vs " << reference << " " << c.nrmse * 100 << " %";
    text << ", overruns " << c.overruns << ", rejected " << c.rejected << "\n";
    if (c.max_difference_from_in_process == 0.0) {
      text << "  equals the in-process run of the same config bit for bit\n";
    } else if (c.max_difference_from_in_process > 0.0) {
      text << "  DIFFERS from the in-process run: max |du| = " << std::scientific
           << c.max_difference_from_in_process << std::fixed << " m\n";
    }
    for (const auto& [node, rtt] : c.round_trip) {
      const auto s = runtime::summarize(rtt);
      const auto inj = runtime::summarize(c.injected.at(node));
      text << "  node " << node << " round trip ms: median " << s.median * 1e3 << ", p99 "
           << s.p99 * 1e3 << ", max " << s.max * 1e3 << " (injected mean " << inj.mean * 1e3
           << ")\n";
      links[std::to_string(node)] = {{"round_trip_median", s.median}, {"round_trip_p99", s.p99},
                                     {"round_trip_max", s.max}, {"injected_mean", inj.mean}};
    }
    j.push_back({{"case", c.name}, {"exit_code", c.exit_code}, {"status", c.status},
                 {"steps", c.steps}, {"peak_displacement", c.peak},
                 {"nrmse_vs_reference", c.nrmse >= 0 ? nlohmann::json(c.nrmse) : nlohmann::json()},
                 {"overruns", c.overruns}, {"rejected", c.rejected}, {"links", links},
                 {"max_difference_from_in_process_m",
                  c.max_difference_from_in_process >= 0 ? nlohmann::json(c.max_difference_from_in_process) : nlohmann::json()},
                 {"record", c.record.string()}, {args.format, c.csv.string()}});
  }
  if (args.json)
    std::cout << nlohmann::json{{"output", out.string()}, {"cases", j}}.dump(2) << "\n";
  else
    std::cout << text.str() << "output: " << out.string() << "\n";
  for (const auto& c : outcomes)
    if (c.exit_code != 0)
      throw ExitError(exit_code_of(c.exit_code), "case " + c.name + ": " + c.status);
}

}  // namespace

void add_launch_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "launch", "Run a study distributed on this machine (coordinator + nodes over DDS)");
  auto args = std::make_shared<LaunchArgs>();
  cmd->add_option("config", args->config, "study config (text format)")->required();
  cmd->add_option("--case", args->cases, "case(s) to run; default every case");
  cmd->add_option("--out", args->out, "output folder (records, CSV, plots, logs)");
  cmd->add_option("--domain", args->domain, "DDS domain id (default deployment.domain_id)");
  cmd->add_option("--bin-dir", args->bin_dir,
                  "where rths-coordinator and the node programs are (default: beside rths)");
  cmd->add_option("--timeout", args->timeout, "s per run before the coordinator is killed");
  cmd->add_option("--cpu-placement", args->cpu_placement,
                  "auto: lockstep runs share one CPU (measured faster on 2 cores), real time is "
                  "left to the scheduler; one-cpu; spread")
      ->check(CLI::IsMember({"auto", "one-cpu", "spread"}));
  cmd->add_option("--format", args->format, "each case's table: csv, mat (MATLAB) or h5 (HDF5), as `rths export`")
      ->check(CLI::IsMember({"csv", "mat", "h5"}));
  cmd->add_option("--security", args->security,
                  "DDS Security: the `rths pki init` folder (default deployment.security_dir); "
                  "each process uses its node_<id> folder");
  cmd->add_flag("--no-plots", args->no_plots, "skip the PNG plots");
  cmd->add_flag("--json", args->json, "print the summary as JSON");
  cmd->callback([args] { run_launch(*args); });
}

}  // namespace rths::cli
