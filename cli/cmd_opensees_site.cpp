// rths opensees-site CONFIG [--port 8090] [--listen 127.0.0.1] [--case NAME] [--out DIR]
//   [--domain N] [--no-start-nodes [--secret-file F | --insecure]] [--no-plots]
//   [--accept-timeout S] [--security DIR] [--run-id ID]
// Serves one OpenSees genericClient element (opensees_site/site.h): the study's actuator
// emulators over DDS, the record in OUT/run.rthsrec, node logs, results.csv and the plots of
// opensees_site/outputs.h (unless --no-plots) beside it, the coordinator's summary on stdout.
// Listens on loopback unless --listen names another address. Exit: 0 the client's analysis
// completed; 1 the client was refused or the run stopped (silent client, bad frame, implicit
// iteration, limits, a node lost, no client within --accept-timeout); 2 bad config or flags; 3
// cannot listen, a node program missing, DDS or file error.
#include <iostream>

#include "cli/commands.h"
#include "cli/support.h"
#include "coordinator/program.h"
#include "opensees_site/outputs.h"
#include "opensees_site/site.h"

namespace rths::cli {

namespace {

struct SiteFlags {
  std::string config, case_name, out = "out/opensees_site", listen = "127.0.0.1", run_id, security;
  int port = 8090, domain = -1;
  bool no_start_nodes = false, no_plots = false;
  double accept_timeout = -1;
  security::SecretChoice secret;
};

int serve(const SiteFlags& f) {
  opensees::SiteOptions options;
  options.config = f.config;
  options.case_name = f.case_name;
  options.run_id = f.run_id;
  options.domain = f.domain;
  options.record = std::filesystem::path(f.out) / "run.rthsrec";
  options.log_dir = f.out;
  options.start_nodes = !f.no_start_nodes;
  options.security_dir = f.security;
  options.secret = f.secret;
  options.accept_timeout = std::chrono::milliseconds(
      f.accept_timeout < 0 ? -1 : static_cast<long long>(f.accept_timeout * 1e3));
  std::unique_ptr<opensees::Site> site;
  try {
    site = std::make_unique<opensees::Site>(options);
  } catch (const std::invalid_argument& e) {
    throw ExitError(kExitBadInput, f.config + ": " + e.what());
  }
  if (!opensees::is_loopback(f.listen))
    print_warning("listening on " + f.listen +
                  ": anyone who can reach this address can drive "
                  "the actuators (loopback is the default)");
  std::filesystem::create_directories(f.out);
  opensees::Listener listener(f.listen, f.port);
  std::cerr << "rths opensees-site: listening on " << listener.address() << ":" << listener.port()
            << " for an OpenSees genericClient with " << site->basic_dofs() << " basic DOFs\n";
  opensees::SiteOutcome outcome;
  try {
    outcome = site->serve(listener);
  } catch (const std::runtime_error& e) {
    throw ExitError(std::string(e.what()).rfind("no OpenSees client", 0) == 0 ? kExitRunFailed
                                                                              : kExitEnvironment,
                    e.what());
  }
  if (!outcome.refusal.empty())
    throw ExitError(kExitRunFailed,
                    "refused the OpenSees client " + outcome.client + ": " + outcome.refusal);
  if (outcome.served && std::filesystem::exists(options.record)) {
    try {
      opensees::write_site_outputs(options.record, f.out, !f.no_plots);
    } catch (const std::exception& e) {
      throw ExitError(kExitEnvironment, e.what());
    }
  }
  std::cout << "client: " << outcome.client << " (" << outcome.ending << ")\n"
            << coordinator::summary_text(outcome.run) << "record: " << options.record.string()
            << "\n";
  if (!outcome.ok())
    throw ExitError(
        kExitRunFailed,
        "run failed: " + outcome.run.status +
            (outcome.run.failed_node.empty() ? "" : " (" + outcome.run.failed_node + ")"));
  return kExitOk;
}

}  // namespace

void add_opensees_site_command(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("opensees-site",
                         "Serve an OpenSees genericClient element: its trials drive the study's "
                         "actuator emulators over DDS");
  auto f = std::make_shared<SiteFlags>();
  cmd->add_option("config", f->config, "the site's study: actuators, lag, limits, deployment")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--port", f->port, "TCP port genericClient connects to (-server PORT)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--listen", f->listen,
                  "IPv4 address to listen on; anything but loopback must be asked for here");
  cmd->add_option("--case", f->case_name,
                  "case to run (default: deployment.case_name or reference)");
  cmd->add_option("--out", f->out, "directory for run.rthsrec and the node logs");
  cmd->add_option("--domain", f->domain, "DDS domain id (default: deployment.domain_id)")
      ->check(CLI::Range(0, 232));
  cmd->add_option("--run-id", f->run_id, "run id (default: <study>-<case>-host-pid-time)");
  cmd->add_option("--security", f->security, "`rths pki init` directory (DDS Security)");
  cmd->add_flag("--no-start-nodes", f->no_start_nodes,
                "the actuator emulators run elsewhere (started by hand with this run id)");
  cmd->add_option("--secret-file", f->secret.file,
                  "with --no-start-nodes: the run secret the emulators were given (`rths pki "
                  "secret FILE`); default: $RTHS_RUN_SECRET_FILE");
  cmd->add_flag("--insecure", f->secret.insecure,
                "with --no-start-nodes: run without a run secret or DDS Security");
  cmd->add_flag("--no-plots", f->no_plots, "write results.csv but no plots");
  cmd->add_option("--accept-timeout", f->accept_timeout,
                  "s to wait for the client (default: forever)");
  cmd->callback([f] { serve(*f); });
}

}  // namespace rths::cli
