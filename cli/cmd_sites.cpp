// `rths sites CONFIG`: the distributed run across emulated sites (one network namespace per site,
// DDS unicast between them, per-link lag injected by the nodes). See deploy/sites.h. Its flags,
// refusals and exit codes are `rths launch`'s: a real-time run's platform check comes first (exit 3
// when refused, unless --accept-platform), the record is OUT/<case>.rthsrec, and the exit is the
// coordinator's (2 config, 3 environment) before the run's verdict (1). With --view the page is on
// this host's HOST:PORT while the run goes on; --view-stop gives it the control room's roles.
#include <signal.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "analysis/distributed/distributed_outputs.h"
#include "analysis/study_run/response_envelope_plots.h"
#include "cli/commands.h"
#include "cli/distributed.h"
#include "cli/support.h"
#include "deploy/netns.h"
#include "deploy/sites.h"
#include "rt_check/check.h"
#include "runtime/node/plan.h"
#include "runtime/record/measurements.h"
#include "runtime/record/record.h"
#include "study/study.h"
#include "util/atomic_file.h"
#include "util/process.h"
#include "view/context.h"
#include "view/hand_down.h"
#include "view/server.h"

namespace rths::cli {
namespace {

struct SitesOptions {
  std::string config, check_record;
  NodeProgramOptions programs;
  ResultsOptions results;
  int domain = -1;  // -1: the sites config's / study's domain
  std::int64_t expect_steps = 1;
  double expect_injected = -1.0;
  double platform_seconds = 5.0;
  bool check = false, cleanup = false, accept_platform = false;
  double probe = 0;  // s of the link check (--probe); 0: none
  std::string view;  // HOST:PORT of the live view, empty: none
  bool view_stop = false;
};

// --view: the page at HOST:PORT of this host (its socket made here, in the host's namespace, and
// handed to the coordinator in site_a's: view/hand_down.h), every site by name with its nodes.
// --view-stop adds the control room: a token per role, made here for this run and printed once,
// each in the address its holder opens (the page takes it out of the address bar). Returns the
// socket (-1 without --view), closed by the caller once the run is over.
// The sites as the page groups them (view/hand_down.h): per site its nodes, and of those the ones
// that drive actuators, in the sites config's order.
std::vector<view::SiteLayout> site_layouts(const deploy::SitesPlan& plan) {
  std::vector<view::SiteLayout> layouts;
  for (const auto& site : plan.sites.sites()) {
    view::SiteLayout& layout = layouts.emplace_back();
    layout.name = site.name();
    for (const deploy::NodePlacement& p : plan.placements) {
      if (p.site != site.name()) continue;
      layout.nodes.push_back(p.node_id);
      if (p.kind == "actuator_emulator" || p.kind == "controller")
        layout.lab_nodes.push_back(p.node_id);
    }
  }
  return layouts;
}

int hand_down_view(const SitesOptions& o, const deploy::SitesPlan& plan,
                   deploy::SitesRunOptions& options) {
  if (o.view.empty()) return -1;
  view::HandDown down;
  down.sites = site_layouts(plan);
  std::vector<std::string> labs;
  for (const auto& [lab, nodes] : down.labs()) labs.push_back(lab);
  if (o.view_stop) down.crew = view::Crew::make(labs);
  try {
    down.listen_fd = view::open_listener(view::parse_listen_address(o.view));
  } catch (const std::invalid_argument& e) {
    throw ExitError(kExitBadInput, e.what());
  } catch (const std::runtime_error& e) {
    throw ExitError(kExitEnvironment, e.what());
  }
  view::set_hand_down(down);
  const std::string url = "http://" + view::parse_listen_address(o.view).host + ":" +
                          std::to_string(view::bound_port(down.listen_fd)) + "/";
  options.coordinator_args = {"--view", o.view};
  std::cerr << "rths sites: live view of every site at " << url << "\n";
  if (!down.crew) return down.listen_fd;
  std::cerr << "rths sites: the control room's addresses, for this run only (each carries its "
               "role's token: hand each to its holder alone)\n"
            << "  director (HOLD any lab, STOP): " << url << "?token=" << down.crew->director
            << "\n";
  for (const auto& [lab, token] : down.crew->operators)
    std::cerr << "  operator of " << lab << " (HOLD " << lab << "'s actuators): " << url
              << "?token=" << token << "\n";
  std::cerr << "  viewer (sees only): " << url << "?token=" << down.crew->viewer << std::endl;
  return down.listen_fd;
}

// --cleanup and --check-record: done without a config. Returns whether the command is done.
bool run_maintenance(const SitesOptions& o) {
  if (o.cleanup) {
    const auto removed = deploy::remove_stale_namespaces();
    for (const auto& name : removed) std::cout << "removed stale namespace " << name << "\n";
    if (o.config.empty()) return true;
  }
  if (o.check_record.empty()) return false;
  try {
    std::cout << deploy::check_record(o.check_record, o.expect_steps, o.expect_injected);
  } catch (const std::runtime_error& e) {
    throw ExitError(kExitRunFailed, std::string("record check failed: ") + e.what());
  }
  return true;
}

std::filesystem::path output_folder(const SitesOptions& o) {
  if (!o.results.out.empty()) return o.results.out;
  return std::filesystem::path("out") /
         ("sites_" + std::filesystem::path(o.config).stem().string());
}

// Real time: the platform check `rths launch` makes, once, before any namespace or process:
// refused (the deployment's fail-safe or overrun tolerance will not hold here) is exit 3 unless
// --accept-platform. Its summary goes to OUT/platform.json and to the coordinator, which then
// does not measure again. Empty path in lockstep.
std::filesystem::path check_platform_first(const study::PreparedStudy& prepared,
                                           const SitesOptions& o,
                                           const std::filesystem::path& out) {
  if (prepared.config.deployment().clock() != config::Deployment::REAL_TIME) return {};
  rt_check::PlatformCheck check;
  try {
    check = rt_check::check_platform(prepared, o.platform_seconds);
  } catch (const std::runtime_error& e) {
    throw ExitError(kExitEnvironment, std::string("platform check: ") + e.what());
  }
  if (!o.results.json || check.verdict.refused())
    std::cerr << rt_check::summary_text(check.summary);
  if (check.verdict.refused() && !o.accept_platform)
    throw ExitError(kExitEnvironment,
                    "refusing to start: the deployment's fail-safe or overrun tolerance will not "
                    "hold on this machine (numbers and fixes above; `rths rt-check` on the study "
                    "repeats the check); --accept-platform runs anyway and the record says so");
  const std::filesystem::path file = std::filesystem::absolute(out / "platform.json");
  util::AtomicFile json(file);
  json.stream() << nlohmann::json{{"platform", rt_check::summary_json(check.summary)}}.dump(2)
                << "\n";
  json.commit();
  return file;
}

deploy::SitesRunResult run_at_sites(const SitesOptions& o, const deploy::SitesPlan& plan,
                                    const std::filesystem::path& out,
                                    const std::filesystem::path& platform_file) {
  if (const auto reason = deploy::namespace_support()) {
    throw ExitError(kExitEnvironment, "sites: " + *reason);
  }
  deploy::SitesRunOptions options;
  struct CloseAfterRun {
    int fd;
    ~CloseAfterRun() {
      if (fd >= 0) ::close(fd);
    }
  } view_socket{hand_down_view(o, plan, options)};
  options.output_dir = out;
  // OUT/sites.json: the sites as the live page groups them, for `rths view OUT` (the record alone
  // names nodes, not sites).
  std::filesystem::create_directories(out);
  util::AtomicFile layout(out / view::kSitesLayoutFile);
  layout.stream() << view::HandDown{-1, site_layouts(plan), std::nullopt}.sites_json().dump(2)
                  << "\n";
  layout.commit();
  options.platform_file = platform_file;
  options.accept_platform = o.accept_platform;
  if (!o.programs.bin_dir.empty()) options.bin_dir = std::filesystem::path(o.programs.bin_dir);
  ProgressReporter progress("sites", "runs", !o.results.json);
  deploy::SitesRunResult result;
  {
    util::HeldStopSignals signals;
    options.stop_requested = [&signals] { return signals.stop_requested(); };
    try {
      result = deploy::run_sites(plan, options);
    } catch (const deploy::NamespacesUnavailable& e) {
      throw ExitError(kExitEnvironment, std::string("sites: ") + e.what());
    }
  }
  progress.update(1, 1);
  return result;
}

// The figures write_distributed_outputs drew into `out` (each PNG with its SVG beside it): none
// when plots are off or failed (`failed`), as a failed gnuplot writes none.
std::string drawn_figures(const std::filesystem::path& out, const std::string& case_name,
                          bool plots, bool failed) {
  if (!plots || failed) return "";
  std::vector<std::string> pngs;
  for (const std::string& file : analysis::study_plot_files(out))
    if (file.ends_with(".png")) pngs.push_back(file);
  pngs.push_back("links_" + case_name + ".png");
  std::string drawn;
  for (const std::string& png : pngs)
    if (std::filesystem::exists(out / png)) drawn += ", " + png + "/.svg";
  return drawn;
}

// The results as `rths run` and `rths launch` write them, against the lag-free in-process
// reference (analysis/distributed), links labelled by role and site.
void report(const SitesOptions& o, const deploy::SitesPlan& plan,
            const study::PreparedStudy& prepared, const deploy::SitesRunResult& result) {
  std::map<int, std::string> site_of_node;
  for (const deploy::NodePlacement& p : plan.placements) site_of_node[p.node_id] = p.site;
  const std::vector<DistributedRun> runs{
      {result.case_name, result.coordinator_exit,
       result.status == "interrupted" || result.status.rfind("timed out", 0) == 0 ? result.status
                                                                                  : "",
       result.record, result.output_dir.string()}};
  const DistributedResults results =
      analysis::judge_distributed(prepared, runs, print_warning, site_of_node);
  bool plots_failed = false;
  const auto table = analysis::write_distributed_outputs(
      results, result.output_dir, !o.results.no_plots, o.results.format,
      [&plots_failed](const std::string& warning) {
        plots_failed = plots_failed || warning.starts_with("plots not written");
        print_warning(warning);
      });
  if (o.results.json) {
    auto j = deploy::to_json(result);
    j["results"] = analysis::distributed_summary_json(results);
    j["results_file"] = table.string();
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << deploy::to_text(result) << analysis::distributed_summary_text(results)
              << "written: " << table.string()
              << drawn_figures(result.output_dir, result.case_name, !o.results.no_plots,
                               plots_failed)
              << ", summary.txt, summary.json\n";
  }
  // As `rths launch`: the coordinator's own exit (3: this machine, e.g. a refused platform; 2:
  // the config) before the run's verdict.
  fail_if_distributed_failed(results, runs, o.results.allow_unstable);
  if (!result.ok) throw ExitError(kExitRunFailed, "sites: run failed: " + result.status);
}

// --probe: each link as the run uses it (the namespaces, DDS with the run secret, the same nodes
// and injected lag), in real time, for `seconds` of the study's steps on its motion scaled by kProbeScale (the
// commands stay below a nanometre: no actuator moves), no platform measurement. Per link from
// the record: round trip (median, p99, ms), jitter (p99 - median, ms), loss (1 - answers accepted
// / answers due, %; the last ceil(round trip / dt) steps' answers are still on the wire), drift
// (least-squares slope of the round trip against time, ms/s); the verdict: the p99 round trip
// within the critical round trip of the loop as compensated (view::link_context) and the
// largest answer age within the node's answer window (the footer's). Exit 1 when a link fails.
constexpr double kProbeScale = 1e-9;

std::string probe_link(const runtime::LinkSeries& link, std::int64_t steps, double dt,
                       const nlohmann::json& critical, const runtime::AnswerAge& age, bool& ok) {
  const runtime::LagSummary rt = link.round_trip_summary();
  const double due = static_cast<double>(steps) - std::ceil(rt.median / dt);
  const double answers = link.answers.empty() ? 0.0 : static_cast<double>(link.answers.back());
  double n = 0, st = 0, sr = 0, stt = 0, str = 0;
  for (std::size_t i = 0; i < link.round_trip.size(); ++i) {
    const double t = link.time[i], r = link.round_trip[i] * 1e3;
    n += 1, st += t, sr += r, stt += t * t, str += t * r;
  }
  const double drift =
      n > 2 && n * stt - st * st > 0 ? (n * str - st * sr) / (n * stt - st * st) : 0;
  const bool unbounded = critical.value("unbounded", false);
  const double crit_ms = critical.value("ms", 0.0);
  const bool rt_ok = unbounded || (critical.contains("ms") && rt.p99 * 1e3 <= crit_ms);
  const bool age_ok = age.steps_judged() == 0 || age.max_steps() <= age.window_steps();
  ok = ok && rt_ok && age_ok && rt.count > 0;
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(2);
  out << "round trip median " << rt.median * 1e3 << " ms, p99 " << rt.p99 * 1e3 << " ms; jitter "
      << (rt.p99 - rt.median) * 1e3 << " ms (p99 - median); loss "
      << (due > 0 ? 100.0 * std::max(0.0, 1.0 - answers / due) : 100.0) << " %; drift " << drift
      << " ms/s; critical round trip ";
  if (unbounded)
    out << "none (stable for every round trip)";
  else if (critical.contains("ms"))
    out << crit_ms << " ms";
  else
    out << "not known";
  out << " [" << critical.value("label", std::string("")) << "]; answer age ";
  if (age.steps_judged() == 0)
    out << "not judged (a lockstep study waits for each answer)";
  else
    out << "max " << age.max_steps() * dt * 1e3 << " ms of a " << age.window_steps() * dt * 1e3
        << " ms window";
  out << ": " << (rt_ok && age_ok && rt.count > 0 ? "the study can take it" : "TOO SLOW");
  return out.str();
}

void run_probe(const SitesOptions& o, deploy::SitesPlan plan,
               const study::PreparedStudy& prepared) {
  if (const auto reason = deploy::namespace_support())
    throw ExitError(kExitEnvironment, "sites: " + *reason);
  config::GroundMotion& motion = *plan.study.mutable_motion();
  motion.set_scale(kProbeScale * (motion.scale() == 0 ? 1.0 : motion.scale()));
  motion.set_duration(o.probe);
  // In real time, whatever the study's clock: SECONDS are then seconds of the clock, and each
  // link carries an answer a step as a real-time run's does (in lockstep a step waits for them).
  // A lockstep study's loop waits for every answer: its probe gets windows of a second (its
  // answer age is then not judged), so a stalled answer is measured rather than stop the probe.
  config::Deployment& deployment = *plan.study.mutable_deployment();
  const bool lockstep = deployment.clock() != config::Deployment::REAL_TIME;
  if (lockstep) {
    deployment.set_answer_window_ms(1000);
    deployment.set_command_watchdog_ms(1000);
    deployment.set_max_overrun_fraction(-1);
  }
  deployment.set_clock(config::Deployment::REAL_TIME);
  deploy::SitesRunOptions options;
  options.output_dir = output_folder(o) / "probe";
  options.accept_platform = true;
  options.platform_seconds = 0;  // the links are measured here, not the machine
  if (!o.programs.bin_dir.empty()) options.bin_dir = std::filesystem::path(o.programs.bin_dir);
  const deploy::SitesRunResult result = deploy::run_sites(plan, options);
  const runtime::RunMeasurements measured =
      runtime::measure_run(runtime::read_record(result.record));
  const nlohmann::json critical =
      view::link_context(prepared, plan.study.deployment().case_name())["critical_round_trip"];
  std::map<int, runtime::AnswerAge> ages;
  for (const runtime::NodeRejects& n : measured.footer.node_rejects())
    ages[n.node_id()] = n.answer_age();
  std::map<int, std::string> site_of;
  for (const deploy::NodePlacement& p : plan.placements) site_of[p.node_id] = p.site;
  bool ok = result.coordinator_exit == 0 || result.status.find("overrun") != std::string::npos;
  std::cout << "probe: " << o.probe << " s of the study's steps on its links (" << result.status
            << ")\n";
  for (const auto& [id, link] : measured.links)
    std::cout << "  link to node " << id << " (site " << site_of[id] << "): "
              << probe_link(link, measured.steps.steps(), prepared.base.dt, critical,
                            lockstep ? runtime::AnswerAge() : ages[id], ok)
              << "\n";
  if (!ok) throw ExitError(kExitRunFailed, "probe: a link is too slow for the study (above)");
}

void run(const SitesOptions& o) {
  if (run_maintenance(o)) return;
  if (o.config.empty()) throw ExitError(kExitBadInput, "sites: CONFIG is required");
  if (o.view_stop && o.view.empty())
    throw ExitError(kExitBadInput, "--view-stop needs --view HOST:PORT");
  auto plan = deploy::load_sites(o.config);
  if (!o.programs.security.empty())
    plan.study.mutable_deployment()->set_security_dir(
        std::filesystem::absolute(o.programs.security).string());
  if (o.domain >= 0) plan.study.mutable_deployment()->set_domain_id(o.domain);
  // Paths in plan.study are absolute. Checked before anything starts (and by --check): the
  // case's lag plus the network's on the actuator's path against the critical delay.
  const study::PreparedStudy prepared =
      study::prepare_study(plan.study, plan.study_file.parent_path());
  runtime::check_deployment(prepared);
  analysis::warn_past_critical_delay(prepared, {plan.study.deployment().case_name()},
                                     print_warning);
  if (o.check) {
    std::cout << "sites config ok: " << plan.placements.size() << " processes on "
              << plan.sites.sites_size() << " sites, DDS domain "
              << plan.study.deployment().domain_id() << "\n";
    return;
  }
  const std::filesystem::path out = output_folder(o);
  claim_output_folder(out, plan.study.name(), o.results.force);
  if (o.probe > 0) return run_probe(o, plan, prepared);
  const std::filesystem::path platform_file = check_platform_first(prepared, o, out);
  report(o, plan, prepared, run_at_sites(o, plan, out, platform_file));
}

}  // namespace

void add_sites_command(CLI::App& app) {
  auto options = std::make_shared<SitesOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sites",
      "Run a study distributed across emulated sites: one network namespace per site, DDS "
      "unicast between them, per-link lag injected by the nodes; always torn down. Needs root "
      "(or CAP_SYS_ADMIN + CAP_NET_ADMIN); exit 3 when namespaces are not permitted");
  cmd->add_option("config", options->config, "sites config (rths.deploy.Sites, text format)");
  add_results_options(cmd, options->results,
                      "output folder: record, results, plots, summary, logs, DDS configs (default "
                      "out/sites_<config name>)",
                      ", the columns of `rths run` plus lag per link");
  add_node_program_options(cmd, options->programs);
  cmd->add_option(
         "--domain", options->domain,
         "DDS domain id (default: the sites config's domain_id, else deployment.domain_id)")
      ->check(in_range(study::Quantity::kDdsDomain));
  cmd->add_option("--platform-seconds", options->platform_seconds,
                  "real time: s of platform measurement before the run (default 5)")
      ->check(finite_in(0.1, 600.0));
  cmd->add_flag("--accept-platform", options->accept_platform,
                "real time: run even when the platform check says the fail-safe or the overrun "
                "tolerance will not hold (the record says so)");
  cmd->add_option("--view", options->view,
                  "serve the live view of the run at HOST:PORT of this host (e.g. "
                  "127.0.0.1:8080): every site by name, its nodes, actuators and links")
      ->check([](const std::string& text) {
        try {
          view::parse_listen_address(text);
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      });
  cmd->add_flag("--view-stop", options->view_stop,
                "with --view: the control room, a token per role printed once here (the director "
                "HOLDs any lab and STOPs; each lab's operator HOLDs only that lab's actuators; a "
                "viewer sees only); every press is in the record");
  cmd->add_option("--probe", options->probe,
                  "only measure each link as the run would use it, for this many s of steps "
                  "(the motion scaled by 1e-9: no actuator moves), and say whether the study, "
                  "with its compensation, can take it")
      ->check(finite_in(0.5, 600.0));
  cmd->add_flag("--check", options->check, "only load and check the config");
  cmd->add_flag("--cleanup", options->cleanup,
                "remove namespaces left by killed `rths sites` runs (then run CONFIG, if given)");
  cmd->add_option("--check-record", options->check_record,
                  "only check a record written elsewhere (e.g. by docker/run_container_test.sh)");
  cmd->add_option("--expect-steps", options->expect_steps, "with --check-record: minimum steps")
      ->check(in_range(study::Quantity::kCount));
  cmd->add_option("--expect-injected", options->expect_injected,
                  "with --check-record: expected largest median injected lag (s)")
      ->transform(seconds_in(study::Quantity::kLag));
  cmd->callback([options] { run(*options); });
}

}  // namespace rths::cli
