// rths launch CONFIG: run a study's cases distributed on this machine (coordinator, substructure
// node and actuator emulator as separate processes over Cyclone DDS on loopback), one run per
// case through the one launch sequence (runtime/launch/launch.h), then write the results as `rths
// run` does (cli/distributed.h: every case against the lag-free in-process reference, `run`'s
// columns plus lag per link, plots, summary) with each case's run record and process logs. Before
// the first run, each case is checked against its critical delay with the network's lag on the
// actuator's path (warn_past_critical_delay); progress per case goes to stderr. A real-time study
// is checked against this machine first (rt_check/check.h, --platform-seconds of measurement,
// written to OUT/platform.json and handed to every case's coordinator): when its fail-safe or
// overrun tolerance will not hold, nothing starts (exit 3, the numbers and the fix named) unless
// --accept-platform. A study with a benchmark section also gets benchmark.txt/.json (J1-J9 of every
// recorded case but the study's reference, as `rths run`). With --view, each case's coordinator
// serves its live view; once the last has exited, launch serves that case's finished record on
// the same address (view::RecordView, as `rths view` does; its badge as launch judged the case),
// from the run's end until Ctrl-C or --view-for, and exits with the runs' status only then.
// Exit: 0 all runs completed; else the first failing coordinator's status (1 run failed, 2 bad
// config, 3 environment); 1 for a diverged case (unless --allow-unstable or expect_unstable); 2
// for a bad config caught before starting anything.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <optional>
#include <regex>
#include <sstream>

#include "analysis/distributed/distributed_outputs.h"
#include "cli/commands.h"
#include "cli/distributed.h"
#include "cli/support.h"
#include "rt_check/check.h"
#include "runtime/launch/launch.h"
#include "study/study.h"
#include "util/process.h"
#include "view/record_view.h"
#include "view/server.h"

namespace rths::cli {
namespace {

struct LaunchArgs {
  std::string config;
  NodeProgramOptions programs;
  ResultsOptions results;
  std::vector<std::string> cases;
  int domain = -1;
  double timeout = 0;
  std::string cpu_placement = "auto";
  double platform_seconds = 5.0;
  bool accept_platform = false;
  std::string view;  // HOST:PORT of the live view, empty: none
  bool view_stop = false;
  double view_for =
      -1;  // s the finished run stays on the view after the last case; < 0: until Ctrl-C
};

// How long the port of a coordinator's live view, just exited, may stay held before launch can
// listen on it: a process's sockets close as it exits, before its parent learns of the exit, so
// this only covers a machine too busy to finish the close at once.
constexpr std::chrono::milliseconds kPortHandOver{2000};

std::filesystem::path case_log_dir(const std::filesystem::path& out, const std::string& name) {
  return out / "logs" / name;
}

// Real time: the platform check once for every case; its summary file, or empty in lockstep.
std::filesystem::path check_platform_first(const study::PreparedStudy& prepared,
                                           const LaunchArgs& args,
                                           const std::filesystem::path& out) {
  if (prepared.config.deployment().clock() != config::Deployment::REAL_TIME) return {};
  rt_check::PlatformCheck check;
  try {
    check = rt_check::check_platform(prepared, args.platform_seconds);
  } catch (const std::runtime_error& e) {
    throw ExitError(kExitEnvironment, std::string("platform check: ") + e.what());
  }
  if (!args.results.json || check.verdict.refused())
    std::cerr << rt_check::summary_text(check.summary);
  if (check.verdict.refused() && !args.accept_platform)
    throw ExitError(kExitEnvironment,
                    "refusing to start: the deployment's fail-safe or overrun tolerance will not "
                    "hold on this machine (numbers and fixes above; `rths rt-check CONFIG` "
                    "repeats the check); --accept-platform runs anyway and the records say so");
  const std::filesystem::path file = out / "platform.json";
  std::ofstream(file) << nlohmann::json{{"platform", rt_check::summary_json(check.summary)}}.dump(
      2);
  return file;
}

// --view / --view-stop as the coordinator's arguments; with --view-stop the stop's token is made
// here (loopback included: any web page may POST to 127.0.0.1), handed down in the environment
// (never on a command line) and printed in the address to open, as Jupyter does.
std::vector<std::string> view_arguments(const LaunchArgs& args) {
  if (args.view.empty()) {
    if (args.view_stop) throw ExitError(kExitBadInput, "--view-stop needs --view HOST:PORT");
    if (args.view_for >= 0) throw ExitError(kExitBadInput, "--view-for needs --view HOST:PORT");
    return {};
  }
  try {
    view::parse_listen_address(args.view);  // refused here, before any case starts
  } catch (const std::invalid_argument& e) {
    throw ExitError(kExitBadInput, e.what());
  }
  std::string token;
  if (args.view_stop) {
    token = view::make_token();
    ::setenv("RTHS_VIEW_TOKEN", token.c_str(), 1);
  }
  std::cerr << "rths launch: live view of each case at http://" << args.view << "/"
            << (args.view_stop ? "?token=" + token + " with a stop button" : "") << "\n";
  std::vector<std::string> out{"--view", args.view};
  if (args.view_stop) out.push_back("--view-stop");
  return out;
}

// With --json, stdout carries the JSON document alone: log lines (a node that outlives the
// coordinator, a CPU left unpinned) go to stderr.
void keep_stdout_for_json(const LaunchArgs& args) {
  if (!args.results.json) return;
  spdlog::default_logger()->sinks() = {std::make_shared<spdlog::sinks::stderr_color_sink_mt>()};
}

study::PreparedStudy prepare_or_exit(const config::Study& study,
                                     const std::filesystem::path& config_path) {
  try {
    study::PreparedStudy prepared = study::prepare_study(study, config_path.parent_path());
    for (const std::string& warning : prepared.warnings) print_warning(warning);
    return prepared;
  } catch (const std::invalid_argument& e) {
    throw ExitError(kExitBadInput, e.what());
  }
}

std::filesystem::path output_folder(const LaunchArgs& args, const config::Study& study) {
  if (!args.results.out.empty()) return args.results.out;
  if (!study.output().directory().empty())
    return std::filesystem::path(study.output().directory()) / "distributed";
  return "rths_launch_" + study.name();
}

// The launch of one case as the flags and the run's folders say.
runtime::LaunchOptions case_options(const LaunchArgs& args, const std::string& name,
                                    const std::filesystem::path& out,
                                    const std::filesystem::path& platform_file) {
  runtime::LaunchOptions options;
  options.config = args.config;
  options.case_name = name;
  options.domain = args.domain;
  options.programs_dir = args.programs.bin_dir;
  options.record = out / (name + ".rthsrec");
  options.log_dir = case_log_dir(out, name);
  options.timeout = args.timeout;
  options.security_dir = args.programs.security;
  options.platform_file = platform_file;
  options.accept_platform = args.accept_platform;
  options.cpu_placement = args.cpu_placement == "one-cpu"  ? runtime::CpuPlacement::kOneCpu
                          : args.cpu_placement == "spread" ? runtime::CpuPlacement::kSpread
                                                           : runtime::CpuPlacement::kAuto;
  options.coordinator_args = view_arguments(args);
  // --format h5: each case's steps also in OUT/<case>.h5, written as the run goes.
  if (args.results.format == "h5")
    for (const std::string& a : {std::string("--h5"), (out / (name + ".h5")).string()})
      options.coordinator_args.push_back(a);
  return options;
}

// Runs each case in turn (a Ctrl-C stops the children in order and ends the loop).
std::vector<DistributedRun> run_cases(const LaunchArgs& args, const std::vector<std::string>& names,
                                      const std::filesystem::path& out,
                                      const std::filesystem::path& platform_file,
                                      const util::HeldStopSignals& signals) {
  std::vector<DistributedRun> runs;
  ProgressReporter progress("launch", "cases", !args.results.json);
  for (const std::string& name : names) {
    runtime::LaunchOptions options = case_options(args, name, out, platform_file);
    options.stop_requested = [&signals] { return signals.stop_requested(); };
    std::filesystem::remove(options.record);
    if (!args.results.json) std::cerr << "rths launch: case " << name << " ...\n";
    runtime::LaunchResult result;
    try {
      result = runtime::launch_run(options);
    } catch (const std::invalid_argument& e) {
      throw ExitError(kExitBadInput, e.what());
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, e.what());
    }
    runs.push_back({result.case_name, result.coordinator_exit, result.status, options.record,
                    options.log_dir.string()});
    if (result.coordinator_exit != 0)
      std::cerr << "rths launch: case " << name << " failed (exit " << result.coordinator_exit
                << (result.status.empty() ? "" : ", " + result.status) << "); logs in "
                << options.log_dir.string() << "\n";
    progress.update(runs.size(), names.size());
    if (result.status == "interrupted") break;
  }
  return runs;
}

// The address the live view of a case listened on: --view's, with the port its coordinator
// printed ("live view at http://HOST:PORT/") when --view asked for any free one (port 0); port 0
// still when the log names none.
view::ListenAddress live_view_address(const LaunchArgs& args, const std::filesystem::path& out,
                                      const std::string& case_name) {
  view::ListenAddress address = view::parse_listen_address(args.view);
  if (address.port != 0) return address;
  std::ifstream log(case_log_dir(out, case_name) / "coordinator.log");
  const std::regex printed(R"(live view at http://\S+:(\d+)/)");
  std::smatch found;
  for (std::string line; std::getline(log, line);)
    if (std::regex_search(line, found, printed)) address.port = std::stoi(found[1]);
  return address;
}

// How launch judged the case `name` against the lag-free run: its summary table's status, why,
// and whether launch fails on it (fail_if_distributed_failed's rules); nothing when it has no
// record to judge.
std::optional<view::JudgedCase> judged_case(const DistributedResults& results,
                                            const std::string& name, bool allow_unstable) {
  for (std::size_t i = 0; i < results.outcome.cases.size(); ++i) {
    const analysis::CaseOutcome& c = results.outcome.cases[i];
    if (c.name != name) continue;
    view::JudgedCase judged{
        c.status + (c.diverged() && c.expect_unstable ? " (expected)" : ""), c.status_detail,
        c.status != "completed" && !(c.diverged() && (c.expect_unstable || allow_unstable))};
    const auto& difference = results.facts[i].difference_from_in_process;
    if (!judged.fails && difference && difference->differs())
      judged = {"differs from the in-process run",
                "the lockstep run differs from the in-process run from step " +
                    std::to_string(*difference->first_step),
                true};
    return judged;
  }
  return std::nullopt;
}

// With --view, once the runs are over: the last case's finished record served where its live
// view was, so an open page stays (and a reload shows the whole run), its badge saying how
// launch judged it. Nothing without --view, with --view-for 0, after a Ctrl-C (which means:
// leave now) or without a record to show.
std::unique_ptr<view::RecordView> keep_view(const LaunchArgs& args,
                                            const std::filesystem::path& out,
                                            const std::vector<DistributedRun>& runs,
                                            const DistributedResults& results) {
  if (args.view.empty() || args.view_for == 0 || runs.empty()) return nullptr;
  const DistributedRun& last = runs.back();
  if (last.launcher_status == "interrupted" || !std::filesystem::exists(last.record))
    return nullptr;
  try {
    return std::make_unique<view::RecordView>(
        last.record, live_view_address(args, out, last.case_name), kPortHandOver,
        judged_case(results, last.case_name, args.results.allow_unstable));
  } catch (const std::exception& e) {
    print_warning(std::string("the view cannot stay after the run: ") + e.what());
    return nullptr;
  }
}

// Serves the kept view until `until` (nothing: for ever) or a Ctrl-C, saying so last, after the
// summary: why the command has not returned yet.
void hold_kept_view(view::RecordView& kept, const std::string& case_name, double seconds,
                    std::optional<std::chrono::steady_clock::time_point> until,
                    const util::HeldStopSignals& signals) {
  std::ostringstream how_long;
  how_long << "for " << seconds << " s from the run's end (or until Ctrl-C)";
  std::cerr << "rths launch: the view stays on the finished run of case " << case_name << " at "
            << kept.url() << " " << (until ? how_long.str() : "until Ctrl-C") << std::endl;
  kept.serve_until(until, [&signals] { return signals.stop_requested(); });
}

void report(const LaunchArgs& args, const study::PreparedStudy& prepared,
            const std::filesystem::path& out, const std::vector<DistributedRun>& runs,
            const DistributedResults& results) {
  const auto table = analysis::write_distributed_outputs(results, out, !args.results.no_plots,
                                                         args.results.format, print_warning);
  // J1-J9 of the recorded cases, as `rths run` gives them (before the summary: the JSON summary
  // must stay the last thing printed).
  if (!results.outcome.cases.empty())
    write_benchmark_outputs(prepared, results.outcome, out, !args.results.no_plots,
                            args.results.json);
  if (args.results.json) {
    auto j = analysis::distributed_summary_json(results);
    j["output"] = out.string();
    j["results"] = table.string();
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << analysis::distributed_summary_text(results) << "written: " << table.string()
              << ", summary.txt, summary.json" << (args.results.no_plots ? "" : ", plots") << " in "
              << out.string() << "\n";
  }
  fail_if_distributed_failed(results, runs, args.results.allow_unstable);
}

void run_launch(const LaunchArgs& args) {
  keep_stdout_for_json(args);
  const std::filesystem::path config_path = args.config;
  const config::Study study =
      load_config_as<config::Study>(config_path, "study", study::load_study);
  const study::PreparedStudy prepared = prepare_or_exit(study, config_path);
  std::vector<std::string> names = args.cases;
  if (names.empty())
    for (const auto& c : study.cases()) names.push_back(c.name());
  const std::filesystem::path out = output_folder(args, study);
  claim_output_folder(out, study.name(), args.results.force);
  // Checked before anything starts: the case's lag plus the network's on the actuator's path.
  analysis::warn_past_critical_delay(prepared, names, print_warning);
  const std::filesystem::path platform_file = check_platform_first(prepared, args, out);
  // Ctrl-C stops the runs in order, or ends the view kept after them.
  util::HeldStopSignals signals;
  const std::vector<DistributedRun> runs = run_cases(args, names, out, platform_file, signals);
  const DistributedResults results = analysis::judge_distributed(prepared, runs, print_warning);
  std::unique_ptr<view::RecordView> kept = keep_view(args, out, runs, results);
  std::optional<std::chrono::steady_clock::time_point> until;
  if (args.view_for >= 0) until = seconds_from_now(args.view_for);
  std::exception_ptr failed;  // the runs' exit status (ExitError), given once the view is gone
  try {
    report(args, prepared, out, runs, results);
  } catch (...) {
    failed = std::current_exception();
  }
  if (kept) hold_kept_view(*kept, runs.back().case_name, args.view_for, until, signals);
  if (failed) std::rethrow_exception(failed);
}

}  // namespace

void add_launch_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "launch", "Run a study distributed on this machine (coordinator + nodes over DDS)");
  auto args = std::make_shared<LaunchArgs>();
  cmd->add_option("config", args->config, "study config (text format)")->required();
  cmd->add_option("--case", args->cases, "case(s) to run; default every case");
  add_results_options(cmd, args->results, "output folder (records, results, plots, logs)",
                      ", the columns of `rths run` plus lag per link");
  cmd->add_option("--domain", args->domain, "DDS domain id (default deployment.domain_id)")
      ->check(in_range(study::Quantity::kDdsDomain));
  add_node_program_options(cmd, args->programs);
  cmd->add_option("--timeout", args->timeout, "s per run before the coordinator is stopped")
      ->transform(seconds_in(study::Quantity::kTimeout));
  cmd->add_option("--cpu-placement", args->cpu_placement,
                  "auto: lockstep runs share one CPU (measured faster on 2 cores), real time is "
                  "left to the scheduler; one-cpu; spread")
      ->check(CLI::IsMember({"auto", "one-cpu", "spread"}));
  cmd->add_option("--view", args->view,
                  "serve the live view of each case at HOST:PORT (e.g. 127.0.0.1:8080), then the "
                  "last case's finished run (--view-for); `rths view RECORD` shows any record");
  cmd->add_option("--view-for", args->view_for,
                  "with --view: after the last case, keep serving its finished run at the same "
                  "address for this many seconds (default: until Ctrl-C; 0: not at all)")
      ->transform(seconds_value())
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--view-stop", args->view_stop,
                "the view gets a stop button (HOLD, then STOP), pressed only from the address "
                "printed here (it carries the stop's token)");
  cmd->add_option("--platform-seconds", args->platform_seconds,
                  "real time: s of platform measurement before the runs (default 5)")
      ->check(finite_in(0.1, 600.0));
  cmd->add_flag("--accept-platform", args->accept_platform,
                "real time: run even when the platform check says the fail-safe or the overrun "
                "tolerance will not hold (the records say so)");
  cmd->callback([args] { run_launch(*args); });
}

}  // namespace rths::cli
