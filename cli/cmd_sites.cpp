// `rths sites CONFIG`: the distributed run across emulated sites (one network namespace per site,
// DDS unicast between them, per-link lag injected by the nodes). See deploy/sites.h.
#include <signal.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

#include "cli/commands.h"
#include "deploy/netns.h"
#include "deploy/sites.h"

namespace rths::cli {
namespace {

struct SitesOptions {
  std::string config, out, bin_dir, check_record, security;
  std::int64_t expect_steps = 1;
  double expect_injected = -1.0;
  bool json = false, check = false, cleanup = false;
};

// Ctrl-C / SIGTERM are held pending while the run goes and polled, so that the run's teardown
// (processes, then namespaces) always happens; restores the previous mask on scope exit.
class HeldStopSignals {
 public:
  HeldStopSignals() {
    sigemptyset(&held_);
    sigaddset(&held_, SIGINT);
    sigaddset(&held_, SIGTERM);
    sigaddset(&held_, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &held_, &previous_);
  }
  ~HeldStopSignals() {
    // A signal received meanwhile is consumed here, not delivered after teardown.
    timespec zero{0, 0};
    while (sigtimedwait(&held_, nullptr, &zero) > 0) {
    }
    pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
  }
  bool stop_requested() const {
    sigset_t pending;
    sigpending(&pending);
    return sigismember(&pending, SIGINT) == 1 || sigismember(&pending, SIGTERM) == 1 ||
           sigismember(&pending, SIGHUP) == 1;
  }

 private:
  sigset_t held_{}, previous_{};
};

void run(const SitesOptions& o) {
  if (o.cleanup) {
    const auto removed = deploy::remove_stale_namespaces();
    for (const auto& name : removed) std::cout << "removed stale namespace " << name << "\n";
    if (o.config.empty()) return;
  }
  if (!o.check_record.empty()) {
    try {
      std::cout << deploy::check_record(o.check_record, o.expect_steps, o.expect_injected);
    } catch (const std::runtime_error& e) {
      throw ExitError(kExitRunFailed, std::string("record check failed: ") + e.what());
    }
    return;
  }
  if (o.config.empty()) throw ExitError(kExitBadInput, "sites: CONFIG is required");
  auto plan = deploy::load_sites(o.config);
  if (!o.security.empty())
    plan.study.mutable_deployment()->set_security_dir(std::filesystem::absolute(o.security).string());
  if (o.check) {
    std::cout << "sites config ok: " << plan.placements.size() << " processes on "
              << plan.sites.sites_size() << " sites\n";
    return;
  }
  if (const auto reason = deploy::namespace_support()) {
    throw ExitError(kExitEnvironment, "sites: " + *reason);
  }
  std::filesystem::path out = o.out;
  if (out.empty()) {
    out = std::filesystem::path("out") /
          ("sites_" + std::filesystem::path(o.config).stem().string());
  }
  deploy::SitesRunOptions options;
  options.output_dir = out;
  if (!o.bin_dir.empty()) options.bin_dir = std::filesystem::path(o.bin_dir);
  deploy::SitesRunResult result;
  {
    HeldStopSignals signals;
    options.stop_requested = [&signals] { return signals.stop_requested(); };
    try {
      result = deploy::run_sites(plan, options);
    } catch (const deploy::NamespacesUnavailable& e) {
      throw ExitError(kExitEnvironment, std::string("sites: ") + e.what());
    }
  }
  if (o.json) {
    std::cout << deploy::to_json(result).dump(2) << "\n";
  } else {
    std::cout << deploy::to_text(result);
  }
  if (!result.ok) throw ExitError(kExitRunFailed, "sites: run failed: " + result.status);
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
  cmd->add_option("--out", options->out,
                  "output folder: record, logs, DDS configs (default out/sites_<config name>)");
  cmd->add_option("--bin-dir", options->bin_dir,
                  "folder with rths-coordinator, rths-substructure-node, rths-actuator-emulator");
  cmd->add_option("--security", options->security,
                  "DDS Security: the `rths pki init` folder (default deployment.security_dir); "
                  "each process uses its node_<id> folder");
  cmd->add_flag("--json", options->json, "print the summary as JSON");
  cmd->add_flag("--check", options->check, "only load and check the config");
  cmd->add_flag("--cleanup", options->cleanup,
                "remove namespaces left by killed `rths sites` runs (then run CONFIG, if given)");
  cmd->add_option("--check-record", options->check_record,
                  "only check a record written elsewhere (e.g. by docker/run_container_test.sh)");
  cmd->add_option("--expect-steps", options->expect_steps, "with --check-record: minimum steps");
  cmd->add_option("--expect-injected", options->expect_injected,
                  "with --check-record: expected largest median injected lag (s)");
  cmd->callback([options] { run(*options); });
}

}  // namespace rths::cli
