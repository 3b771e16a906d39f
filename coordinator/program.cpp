#include "coordinator/program.h"

#include <spdlog/async.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string_view>
#include <tuple>
#include <vector>

#include "coordinator/answer_age.h"
#include "results/record_h5.h"
#include "rt_check/check.h"
#include "runtime/launch/launch.h"
#include "runtime/node/node_main.h"
#include "runtime/node/plan.h"
#include "runtime/record/node_health.h"
#include "security/check.h"
#include "security/pki.h"
#include "security/run_secret.h"
#include "security/secret_options.h"
#include "transport/dds_endpoint.h"
#include "view/context.h"
#include "view/feed.h"
#include "view/hand_down.h"
#include "view/server.h"

namespace rths::coordinator {

namespace {

std::string reject_text(const runtime::Counters& c) {
  return "foreign-run " + std::to_string(c.foreign_run()) + ", garbage " +
         std::to_string(c.garbage()) + ", duplicate " + std::to_string(c.duplicate()) + ", stale " +
         std::to_string(c.stale()) + ", out-of-order " + std::to_string(c.out_of_order()) +
         ", unknown-node " + std::to_string(c.unknown_node()) + ", not-entitled " +
         std::to_string(c.not_entitled()) + ", out-of-range " + std::to_string(c.out_of_range());
}

// Names the newest message dropped for want of a MAC, when one was.
std::string unauthenticated_text(const RunOutcome& o) {
  std::string text = ", unauthenticated ";
  text += std::to_string(o.unauthenticated.count);
  if (o.unauthenticated.count == 0) return text;
  text += " (dropped unread; newest: ";
  text += o.unauthenticated.last;
  text += ")";
  return text;
}

}  // namespace

std::string summary_text(const RunOutcome& o) {
  std::ostringstream out;
  const auto& c = o.counters;
  out << "status: " << o.status
      << (o.failed_node.empty() ? "" : " [" + o.failed_node + "]")
      // The record holds the initial state and one row per commanded step, as `rths run` counts.
      << "\nsteps: " << c.steps() + 1 << " recorded (" << c.steps() << " commanded) in "
      << o.wall_seconds << " s"
      << "\nrejected: " << reject_text(c) << unauthenticated_text(o)
      << "\noverruns: " << c.overruns() << " (worst streak " << c.worst_overrun_streak()
      << "), max lateness " << o.max_lateness * 1e3
      << " ms"
      // In real time a link whose round trip is longer than a step answers later by design; the
      // count says how often the integrator used an older answer, not that anything failed.
      << "\nsteps on an older answer (by design where a link's round trip exceeds the step): "
      << c.late_feedback() << " (worst streak " << c.worst_late_streak() << ")\n";
  // The loop thread's own CPU time per step: the load-independent figure the real-time tests
  // bound (tests/support/real_time_run.h), since a loaded machine stretches the step's wall time
  // but not the CPU time its code burns.
  if (o.step_cpu.count > 0)
    out << "loop CPU per step: median " << o.step_cpu.median * 1e3 << " ms, p99 "
        << o.step_cpu.p99 * 1e3 << " ms, max " << o.step_cpu.max * 1e3 << " ms over "
        << o.step_cpu.count << " steps\n";
  if (c.servo_ticks() > 0)
    out << "servo loops: " << c.servo_overruns() << " overruns in " << c.servo_ticks()
        << " periods ("
        << 100.0 * static_cast<double>(c.servo_overruns()) / static_cast<double>(c.servo_ticks())
        << " %, as of each emulator's last heartbeat)\n";
  // Each node's own transport drops (its heartbeat's count) beside its rejects.
  for (const runtime::NodeRejects& n : o.node_rejects)
    out << n.label() << " DDS messages rejected: " << reject_text(n.rejected())
        << ", unauthenticated " << n.rejected().unauthenticated()
        << (n.final() ? "" : " (as of its last heartbeat; no report on STOP)") << "\n";
  for (const runtime::NodeRejects& n : o.node_rejects)
    out << runtime::controller_link_text(n) << runtime::answer_age_text(n);
  for (const LinkLagStats& l : o.links)
    out << l.label << ": round trip median " << l.round_trip.median * 1e3 << " ms, p99 "
        << l.round_trip.p99 * 1e3 << " ms, max " << l.round_trip.max * 1e3 << " ms; injected mean "
        << l.injected.mean * 1e3 << " ms\n";
  return out.str();
}

namespace {

struct PlatformArgs {
  std::string file;
  double seconds = 3.0;
  bool accept = false;
};

// The platform summary a real-time run records: read from --platform, else measured for
// --platform-seconds (0: not measured, only with --accept-platform). Throws PlatformRefused when
// the check refuses the deployment and --accept-platform was not given.
struct PlatformRefused : std::runtime_error {
  using std::runtime_error::runtime_error;
};

runtime::PlatformSummary platform_summary(const study::PreparedStudy& prepared,
                                          const PlatformArgs& args) {
  runtime::PlatformSummary summary;
  if (!args.file.empty()) {
    summary = rt_check::read_summary_file(args.file);
  } else if (args.seconds > 0) {
    summary = rt_check::check_platform(prepared, args.seconds).summary;
  } else {
    if (!args.accept)
      throw std::invalid_argument("--platform-seconds 0 (not measured) needs --accept-platform");
    summary.set_verdict("not measured (--platform-seconds 0)");
    summary.set_refused(true);
  }
  if (summary.refused() && !args.accept)
    throw PlatformRefused(rt_check::summary_text(summary) +
                          "refusing to start: the fail-safe or the overrun tolerance will not hold "
                          "on this machine; change the deployment as above, or run anyway with "
                          "--accept-platform (the record says so)");
  summary.set_accepted_override(summary.refused());
  return summary;
}

// The live view (--view): a feed of the record and its server, and what a launcher handed down
// (view/hand_down.h: a listening socket, the sites, the crew's tokens and so the control room).
// Bad address or no record: std::invalid_argument; an address that cannot be bound or page
// files missing: runtime_error.
struct LiveView {
  std::unique_ptr<view::Feed> feed;
  std::unique_ptr<view::ControlDesk> desk;
  std::unique_ptr<view::ViewServer> server;
};

LiveView start_view(const std::string& address_text, bool allow_stop, const std::string& record,
                    const study::PreparedStudy& prepared, const std::string& case_name,
                    std::atomic<bool>& stop_request) {
  if (record.empty())
    throw std::invalid_argument("--view needs --record: the view follows the run record");
  view::ServerOptions options;
  options.address = view::parse_listen_address(address_text);
  options.allow_stop = allow_stop;
  // The stop's token, loopback included (any web page may POST to 127.0.0.1). The launcher may
  // hand it down (RTHS_VIEW_TOKEN) to print it itself; never on argv.
  const char* given = std::getenv("RTHS_VIEW_TOKEN");
  if (allow_stop) options.token = given && *given ? given : view::make_token();
  options.on_stop = [&stop_request] { stop_request.store(true); };
  const view::HandDown down = view::handed_down();
  options.listen_fd = down.listen_fd;
  LiveView live;
  if (down.crew) live.desk = std::make_unique<view::ControlDesk>(*down.crew, down.labs());
  options.desk = live.desk.get();
  live.feed = std::make_unique<view::Feed>();
  // The prediction runs the case in process here, before the run starts (never on its loop).
  view::describe_run(*live.feed, prepared, case_name);
  nlohmann::json context = live.feed->context();
  if (!down.sites.empty()) context["sites"] = down.sites_json();
  // Real time: each node's answer window as the loop judges it (its link's injected lag added),
  // at the run's start, for the page's answer age.
  const config::Deployment deployment =
      runtime::with_default_nodes(prepared.config.deployment(), prepared.base);
  if (deployment.clock() == config::Deployment::REAL_TIME)
    for (const config::NodeSpec& node : deployment.nodes())
      context["answer_window_steps_by_node"][std::to_string(node.id())] =
          AnswerWindow(deployment, node, prepared.base.dt).steps(0.0);
  live.feed->set_context(context);
  live.server = std::make_unique<view::ViewServer>(*live.feed, options);
  // A token handed down by the launcher was printed there: this output may be a log file.
  const bool token_made_here = allow_stop && !(given && *given);
  std::cout << "rths-coordinator: live view at "
            << (token_made_here ? live.server->page_url() : live.server->url())
            << (allow_stop ? " (stop button on)" : "") << (live.desk ? " (control room)" : "")
            << std::endl;
  if (!options.address.loopback())
    std::cout << "rths-coordinator: the view listens beyond loopback: anyone who reaches "
              << live.server->url() << " sees the run" << std::endl;
  return live;
}

struct ProgramArgs {
  std::string config_path, case_name, run_id, record, h5, security_dir;
  security::SecretChoice secret;
  int domain = -1;
  PlatformArgs platform;
  std::string view_address;
  bool view_stop = false;
};

void add_arguments(CLI::App& app, ProgramArgs& a) {
  app.add_option("--platform", a.platform.file,
                 "real time: the platform check to use (`rths rt-check CONFIG --json` output) "
                 "instead of measuring");
  app.add_option("--platform-seconds", a.platform.seconds,
                 "real time: s of platform measurement before the run (default 3; 0 = none, "
                 "with --accept-platform)")
      ->check(runtime::finite_in(0.0, 20.0));
  app.add_flag("--accept-platform", a.platform.accept,
               "real time: run even when the platform check refuses the deployment (recorded)");
  app.add_option("--config", a.config_path, "study config (text format)")->required();
  app.add_option("--case", a.case_name, "case to run (default: deployment.case_name or reference)");
  app.add_option("--run-id", a.run_id, "run id (default: host-pid-time)");
  app.add_option("--record", a.record, "run record file (length-delimited protobuf)");
  app.add_option("--h5", a.h5,
                 "the record's steps also written to this HDF5 file as the run goes (compressed "
                 "blocks of 1024 steps, each flushed: a run killed mid-way keeps them); needs "
                 "--record");
  app.add_option("--domain", a.domain, "DDS domain id (default: deployment.domain_id)");
  security::add_secret_options(
      app, a.security_dir, a.secret,
      "the coordinator's folder from `rths pki init` (DIR/node_0); default: "
      "deployment.security_dir",
      "any participant on the domain can then speak as a node until it is pinned");
  app.add_option(
      "--view", a.view_address,
      "serve the live view of the run at HOST:PORT (e.g. 127.0.0.1:8080); needs --record");
  app.add_flag("--view-stop", a.view_stop,
               "the view gets a stop button (HOLD, then STOP), pressed only from the address "
               "printed at start-up (it carries the stop's token)");
}

// Each entry of the record to the live view and to the HDF5 file (either may be absent), on the
// record's writer thread.
class RecordObservers final : public runtime::RecordObserver {
 public:
  void add(runtime::RecordObserver* observer) {
    if (observer) observers_.push_back(observer);
  }
  void on_entry(std::string_view frame) override {
    for (runtime::RecordObserver* o : observers_) o->on_entry(frame);
  }
  bool empty() const { return observers_.empty(); }

 private:
  std::vector<runtime::RecordObserver*> observers_;
};

// Everything a run holds, in the order it is torn down: the coordinator first, then what it
// uses (the record's writer feeds the view and the HDF5 file, so they outlive it).
struct Session {
  std::atomic<bool> stop_request{false};
  LiveView view;
  std::unique_ptr<results::RecordH5Writer> h5;
  RecordObservers observers;
  std::unique_ptr<rt_check::DmaLatencyHold> dma_latency;
  std::unique_ptr<transport::DdsEndpoint> endpoint;
  std::unique_ptr<Coordinator> coordinator;
};

// Real time: the platform gate (PlatformRefused) and /dev/cpu_dma_latency held for the run, so
// CPUs stay out of deep idle states, whose exit adds to wake-ups.
void prepare_real_time(const study::PreparedStudy& prepared, const PlatformArgs& args,
                       CoordinatorOptions& co, Session& session) {
  runtime::check_failsafe_windows(prepared.config.deployment());
  co.platform = platform_summary(prepared, args);
  session.dma_latency = std::make_unique<rt_check::DmaLatencyHold>();
  co.platform->set_dma_latency_held(session.dma_latency->held());
  if (!session.dma_latency->held())
    std::cerr << "rths-coordinator: not holding /dev/cpu_dma_latency: "
              << session.dma_latency->why_not() << "\n";
}

std::unique_ptr<transport::DdsEndpoint> open_endpoint(const config::Study& study, ProgramArgs& a) {
  transport::DdsEndpointOptions options;
  options.domain_id =
      static_cast<std::uint32_t>(a.domain >= 0 ? a.domain : study.deployment().domain_id());
  if (a.security_dir.empty() && !study.deployment().security_dir().empty())
    a.security_dir = security::node_dir(
        std::filesystem::path(a.config_path).parent_path() / study.deployment().security_dir(),
        security::kCoordinatorNodeId);
  if (!a.security_dir.empty())  // refused here (exit 2), before the participant exists
    options.participant_properties = security::participant_properties(
        security::check_node_security(a.security_dir, security::kCoordinatorNodeId));
  a.secret.dds_security = !a.security_dir.empty();
  options.run_secret = security::resolve_run_secret(a.secret);
  return std::make_unique<transport::DdsEndpoint>(options);
}

// Throws std::invalid_argument for bad input, PlatformRefused or another exception when this
// machine cannot keep the run.
void start_session(ProgramArgs& a, Session& session) {
  const config::Study study = study::load_study(a.config_path);
  study::PreparedStudy prepared =
      study::prepare_study(study, std::filesystem::path(a.config_path).parent_path());
  CoordinatorOptions co;
  if (study.deployment().clock() == config::Deployment::REAL_TIME)
    prepare_real_time(prepared, a.platform, co, session);
  session.endpoint = open_endpoint(study, a);
  co.run_id =
      !a.run_id.empty() ? a.run_id
      : !study.deployment().run_id().empty()
          ? study.deployment().run_id()
          : runtime::make_run_id(study.name() + "-" + study::find_case(study, a.case_name).name());
  co.case_name = a.case_name;
  co.record = a.record;
  if (!a.view_address.empty()) {
    const std::string shown_case =
        a.case_name.empty() ? study.deployment().case_name() : a.case_name;
    session.view = start_view(a.view_address, a.view_stop, a.record, prepared, shown_case,
                              session.stop_request);
    session.observers.add(session.view.feed.get());
    co.stop_request = &session.stop_request;
    co.control = session.view.desk.get();
  }
  if (!a.h5.empty()) {
    if (a.record.empty())
      throw std::invalid_argument("--h5 needs --record: the HDF5 file follows the run record");
    session.h5 = std::make_unique<results::RecordH5Writer>(a.h5);
    session.observers.add(session.h5.get());
  }
  if (!session.observers.empty()) co.record_observer = &session.observers;
  transport::DdsEndpoint* endpoint = session.endpoint.get();
  co.unauthenticated = [endpoint] { return endpoint->unauthenticated(); };
  session.coordinator = std::make_unique<Coordinator>(std::move(prepared), *session.endpoint, co);
}

}  // namespace

int coordinator_main(int argc, char** argv) {
  CLI::App app{"rths-coordinator: the integrator loop of a distributed hybrid test"};
  ProgramArgs args;
  add_arguments(app, args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  // A file size limit (ulimit -f) must fail a record write (EFBIG), which holds the actuators,
  // writes what it can and names the reason, as a full disk's ENOSPC does; its default signal
  // would kill the coordinator with no HOLD, no footer and no reason.
  std::signal(SIGXFSZ, SIG_IGN);
  // Log lines leave the loop thread through spdlog's queue; a full queue overwrites the oldest
  // line rather than block the loop.
  spdlog::init_thread_pool(8192, 1);
  spdlog::set_default_logger(spdlog::create_async_nb<spdlog::sinks::stdout_color_sink_mt>("rths"));
  struct FlushLogs {
    ~FlushLogs() { spdlog::shutdown(); }
  } flush_logs;
  Session session;
  try {
    start_session(args, session);
  } catch (const std::invalid_argument& e) {
    std::cerr << "rths-coordinator: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {  // PlatformRefused too: this machine cannot keep the run
    std::cerr << "rths-coordinator: " << e.what() << "\n";
    return 3;
  }
  try {
    const RunOutcome outcome = session.coordinator->run();
    std::cout << summary_text(outcome) << std::flush;
    if (session.view.server)
      session.view.server->shutdown();  // open pages get the run's last state first
    if (!outcome.ok)
      std::cerr << "rths-coordinator: run failed: " << outcome.status
                << (outcome.failed_node.empty() ? "" : " (" + outcome.failed_node + ")") << "\n";
    if (session.h5) {
      session.h5->close();
      if (!session.h5->failure().empty()) {
        // The record holds every step; the HDF5 file asked for is not whole: not a good run.
        std::cerr << "rths-coordinator: " << session.h5->failure() << " (the record " << args.record
                  << " holds every step)\n";
        return outcome.ok || outcome.environment_fault ? 3 : 1;
      }
    }
    return outcome.ok ? 0 : outcome.environment_fault ? 3 : 1;
  } catch (const std::exception& e) {
    std::cerr << "rths-coordinator: " << e.what() << "\n";
    return 3;
  }
}

}  // namespace rths::coordinator
