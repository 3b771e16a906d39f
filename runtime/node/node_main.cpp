#include "runtime/node/node_main.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>

#include "runtime/node/node_loop.h"
#include "runtime/node/plan.h"
#include "security/check.h"
#include "security/pki.h"
#include "security/run_secret.h"
#include "study/study.h"
#include "transport/dds_endpoint.h"

namespace rths::runtime {

namespace {

// The study at `path` checked as `rths run` checks it (parsed and validated, prepared: its motion
// read, its reference case's deployment planned), so a bad study is refused here at start with
// the message `run` gives, never after waiting for a coordinator; then its deployment.
config::Deployment checked_deployment(const std::string& path) {
  const config::Study study = core::load_study(path);
  check_deployment(core::prepare_study(study, std::filesystem::path(path).parent_path()));
  return study.deployment();
}

}  // namespace

int node_main(int argc, char** argv, const std::string& program, const ServiceFactory& factory) {
  CLI::App app{program + ": an rths node; the coordinator assigns its part of the study"};
  int node_id = 0;
  int domain = -1;
  std::string config_path, run_id, security_dir;
  security::SecretChoice secret;
  NodeLoopOptions loop;
  app.add_option("--node-id", node_id, "this node's id in the deployment (>= 1)")->required();
  app.add_option("--domain", domain, "DDS domain id (default: the config's deployment.domain_id)");
  app.add_option("--config", config_path,
                 "study config: checked as `rths run` checks it (a bad one: exit 2 at start), "
                 "then read for its domain id, run id and security_dir");
  app.add_option("--run-id", run_id,
                 "the run this node joins (default: the config's deployment.run_id); required");
  app.add_option("--assign-timeout", loop.assign_timeout,
                 "s to wait for an assignment (finite, > 0)");
  app.add_option("--security", security_dir,
                 "DDS Security: this node's folder from `rths pki init` (DIR/node_<id>); default: "
                 "the config's deployment.security_dir");
  app.add_option("--secret-file", secret.file,
                 "the run secret (`rths pki secret FILE`, mode 0600); default: $" +
                     std::string(security::kSecretFileEnv) + " or $" + security::kSecretEnv);
  app.add_flag("--insecure", secret.insecure,
               "run without a run secret or DDS Security: any participant on the domain can then "
               "speak as the coordinator to this node");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  transport::DdsEndpointOptions options;
  try {
    if (node_id < 1) throw std::invalid_argument("--node-id must be >= 1");
    if (!(std::isfinite(loop.assign_timeout) && loop.assign_timeout > 0))  // NaN too
      throw std::invalid_argument(
          fmt::format("--assign-timeout {} s is not a time (finite, > 0)", loop.assign_timeout));
    if (domain < 0 && config_path.empty()) throw std::invalid_argument("give --domain or --config");
    if (!config_path.empty()) {
      const config::Deployment deployment = checked_deployment(config_path);
      if (domain < 0) domain = deployment.domain_id();
      if (run_id.empty()) run_id = deployment.run_id();
      if (security_dir.empty() && !deployment.security_dir().empty())
        security_dir = security::node_dir(
            std::filesystem::path(config_path).parent_path() / deployment.security_dir(), node_id);
    }
    if (!security_dir.empty())  // refused here, before the participant exists
      options.participant_properties =
          security::participant_properties(security::check_node_security(security_dir, node_id));
    secret.dds_security = !security_dir.empty();
    options.run_secret = security::resolve_run_secret(secret);
    if (run_id.empty())
      throw std::invalid_argument(
          "give --run-id (or deployment.run_id in --config): the coordinator accepts only "
          "announcements of its own run, and this node only that run's assignment");
  } catch (const std::exception& e) {
    std::cerr << program << ": " << e.what() << "\n";
    return 2;
  }
  try {
    options.domain_id = static_cast<std::uint32_t>(domain);
    options.coordinator = false;
    options.node_id = node_id;
    transport::DdsEndpoint endpoint(options);
    auto service = factory(node_id, run_id);
    service->set_unauthenticated_source([&endpoint] { return endpoint.unauthenticated_count(); });
    const int code = run_node(endpoint, *service, loop);
    const transport::Unauthenticated dropped = endpoint.unauthenticated();
    if (dropped.count > 0)
      spdlog::warn("{}: {} messages dropped unread as unauthenticated (no valid MAC); newest: {}",
                   service->label(), dropped.count, dropped.last);
    return code;
  } catch (const std::exception& e) {
    std::cerr << program << " (node " << node_id << "): " << e.what() << "\n";
    return 3;
  }
}

}  // namespace rths::runtime
