#include "coordinator/program.h"

#include <spdlog/async.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdlib>
#include <iostream>
#include <tuple>
#include <sstream>

#include "runtime/launch.h"
#include "runtime/plan.h"
#include "security/check.h"
#include "security/pki.h"
#include "transport/dds_endpoint.h"
#include "view/context.h"
#include "view/feed.h"
#include "view/server.h"

namespace rths::coordinator {

namespace {

std::string reject_text(const runtime::Counters& c) {
  return "foreign-run " + std::to_string(c.foreign_run()) + ", garbage " +
         std::to_string(c.garbage()) + ", duplicate " + std::to_string(c.duplicate()) +
         ", stale " + std::to_string(c.stale()) + ", out-of-order " +
         std::to_string(c.out_of_order()) + ", unknown-node " + std::to_string(c.unknown_node()) +
         ", not-entitled " + std::to_string(c.not_entitled()) + ", out-of-range " +
         std::to_string(c.out_of_range());
}

}  // namespace

std::string summary_text(const RunOutcome& o) {
  std::ostringstream out;
  const auto& c = o.counters;
  out << "status: " << o.status << (o.failed_node.empty() ? "" : " [" + o.failed_node + "]")
      // The record holds the initial state and one row per commanded step, as `rths run` counts.
      << "\nsteps: " << c.steps() + 1 << " recorded (" << c.steps() << " commanded) in "
      << o.wall_seconds << " s"
      << "\nrejected: " << reject_text(c)
      << "\noverruns: " << c.overruns() << " (worst streak " << c.worst_overrun_streak()
      << "), max lateness " << o.max_lateness * 1e3 << " ms"
      // In real time a link whose round trip is longer than a step answers later by design; the
      // count says how often the integrator used an older answer, not that anything failed.
      << "\nsteps on an older answer (by design where a link's round trip exceeds the step): "
      << c.late_feedback() << " (worst streak " << c.worst_late_streak() << ")\n";
  if (c.servo_ticks() > 0)
    out << "servo loops: " << c.servo_overruns() << " overruns in " << c.servo_ticks()
        << " periods (" << 100.0 * static_cast<double>(c.servo_overruns()) / static_cast<double>(c.servo_ticks())
        << " %, as of each emulator's last heartbeat)\n";
  for (const runtime::NodeRejects& n : o.node_rejects)
    out << n.label() << " rejected: " << reject_text(n.rejected())
        << (n.final() ? "" : " (as of its last heartbeat; no report on STOP)") << "\n";
  for (const LinkLagStats& l : o.links)
    out << l.label << ": round trip median " << l.round_trip.median * 1e3 << " ms, p99 "
        << l.round_trip.p99 * 1e3 << " ms, max " << l.round_trip.max * 1e3
        << " ms; injected mean " << l.injected.mean * 1e3 << " ms\n";
  return out.str();
}

namespace {

// The live view (--view): a feed of the record and its server. Bad address or no record:
// std::invalid_argument; an address that cannot be bound or page files missing: runtime_error.
std::pair<std::unique_ptr<view::Feed>, std::unique_ptr<view::ViewServer>> start_view(
    const std::string& address_text, bool allow_stop, const std::string& record,
    const core::PreparedStudy& prepared, const std::string& case_name, std::atomic<bool>& stop_request) {
  if (record.empty()) throw std::invalid_argument("--view needs --record: the view follows the run record");
  view::ServerOptions options;
  options.address = view::parse_listen_address(address_text);
  options.allow_stop = allow_stop;
  // The launcher may hand the token down (RTHS_VIEW_TOKEN) to print it itself; never on argv.
  const char* given = std::getenv("RTHS_VIEW_TOKEN");
  if (allow_stop && !options.address.loopback())
    options.token = given && *given ? given : view::make_token();
  options.on_stop = [&stop_request] { stop_request.store(true); };
  auto feed = std::make_unique<view::Feed>();
  feed->set_context(view::run_context(prepared, case_name));
  auto server = std::make_unique<view::ViewServer>(*feed, options);
  std::cout << "rths-coordinator: live view at " << server->url()
            << (allow_stop ? " (stop button on)" : "")
            << (options.token.empty() ? "" : "; stop token " + options.token) << std::endl;
  if (!options.address.loopback())
    std::cout << "rths-coordinator: the view listens beyond loopback: anyone who reaches "
              << server->url() << " sees the run" << std::endl;
  return {std::move(feed), std::move(server)};
}

}  // namespace

int coordinator_main(int argc, char** argv) {
  CLI::App app{"rths-coordinator: the integrator loop of a distributed hybrid test"};
  std::string config_path, case_name, run_id, record, security_dir;
  int domain = -1;
  app.add_option("--config", config_path, "study config (text format)")->required();
  app.add_option("--case", case_name, "case to run (default: deployment.case_name or reference)");
  app.add_option("--run-id", run_id, "run id (default: host-pid-time)");
  app.add_option("--record", record, "run record file (length-delimited protobuf)");
  app.add_option("--domain", domain, "DDS domain id (default: deployment.domain_id)");
  app.add_option("--security", security_dir,
                 "DDS Security: the coordinator's folder from `rths pki init` (DIR/node_0); "
                 "default: deployment.security_dir");
  std::string view_address;
  bool view_stop = false;
  app.add_option("--view", view_address,
                 "serve the live view of the run at HOST:PORT (e.g. 127.0.0.1:8080); needs --record");
  app.add_flag("--view-stop", view_stop,
               "the view gets a stop button (HOLD, then STOP); beyond loopback it asks for the "
               "token printed at start-up");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  // Log lines leave the loop thread through spdlog's queue; a full queue overwrites the oldest
  // line rather than block the loop.
  spdlog::init_thread_pool(8192, 1);
  spdlog::set_default_logger(spdlog::create_async_nb<spdlog::sinks::stdout_color_sink_mt>("rths"));
  struct FlushLogs {
    ~FlushLogs() { spdlog::shutdown(); }
  } flush_logs;
  // Declared before the coordinator, so they outlive it (the record's writer feeds the view).
  std::atomic<bool> stop_request{false};
  std::unique_ptr<view::Feed> feed;
  std::unique_ptr<view::ViewServer> server;
  std::unique_ptr<Coordinator> coordinator;
  std::unique_ptr<transport::DdsEndpoint> endpoint;
  try {
    const config::Study study = core::load_study(config_path);
    core::PreparedStudy prepared =
        core::prepare_study(study, std::filesystem::path(config_path).parent_path());
    transport::DdsEndpointOptions options;
    options.domain_id =
        static_cast<std::uint32_t>(domain >= 0 ? domain : study.deployment().domain_id());
    if (security_dir.empty() && !study.deployment().security_dir().empty())
      security_dir = security::node_dir(std::filesystem::path(config_path).parent_path() /
                                            study.deployment().security_dir(),
                                        security::kCoordinatorNodeId);
    if (!security_dir.empty())  // refused here (exit 2), before the participant exists
      options.participant_properties = security::participant_properties(
          security::check_node_security(security_dir, security::kCoordinatorNodeId));
    endpoint = std::make_unique<transport::DdsEndpoint>(options);
    CoordinatorOptions co;
    co.run_id = !run_id.empty() ? run_id
                : !study.deployment().run_id().empty() ? study.deployment().run_id()
                                                       : runtime::make_run_id(study.name() + "-" + runtime::find_case(study, case_name).name());
    co.case_name = case_name;
    co.record = record;
    if (!view_address.empty()) {
      const std::string shown_case = case_name.empty() ? study.deployment().case_name() : case_name;
      std::tie(feed, server) = start_view(view_address, view_stop, record, prepared, shown_case, stop_request);
      co.record_observer = feed.get();
      co.stop_request = &stop_request;
    }
    coordinator = std::make_unique<Coordinator>(std::move(prepared), *endpoint, co);
  } catch (const std::invalid_argument& e) {
    std::cerr << "rths-coordinator: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "rths-coordinator: " << e.what() << "\n";
    return 3;
  }
  try {
    const RunOutcome outcome = coordinator->run();
    std::cout << summary_text(outcome) << std::flush;
    if (server) server->shutdown();  // open pages get the run's last state first
    if (!outcome.ok) std::cerr << "rths-coordinator: run failed: " << outcome.status
                               << (outcome.failed_node.empty() ? "" : " (" + outcome.failed_node + ")")
                               << "\n";
    return outcome.ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "rths-coordinator: " << e.what() << "\n";
    return 3;
  }
}

}  // namespace rths::coordinator
