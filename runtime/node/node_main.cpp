#include "runtime/node/node_main.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>

#include "core/number_text.h"
#include "runtime/node/node_loop.h"
#include "runtime/node/plan.h"
#include "security/check.h"
#include "security/pki.h"
#include "security/run_secret.h"
#include "security/secret_options.h"
#include "study/study.h"
#include "transport/dds_endpoint.h"

namespace rths::runtime {

namespace {

// The study at `path` checked as `rths run` checks it (parsed and validated, prepared: its motion
// read, its reference case's deployment planned), so a bad study is refused here at start with
// the message `run` gives, never after waiting for a coordinator; then its deployment.
config::Deployment checked_deployment(const std::string& path) {
  const config::Study study = study::load_study(path);
  check_deployment(study::prepare_study(study, std::filesystem::path(path).parent_path()));
  return study.deployment();
}

// What the command line gives a node program.
struct NodeArgs {
  int node_id = 0;
  int domain = -1;
  std::string config_path, run_id, security_dir;
  security::SecretChoice secret;
  NodeLoopOptions loop;
};

void add_node_options(CLI::App& app, NodeArgs& a) {
  app.add_option("--node-id", a.node_id, "this node's id in the deployment (>= 1)")->required();
  app.add_option("--domain", a.domain,
                 "DDS domain id (default: the config's deployment.domain_id)");
  app.add_option("--config", a.config_path,
                 "study config: checked as `rths run` checks it (a bad one: exit 2 at start), "
                 "then read for its domain id, run id and security_dir");
  app.add_option("--run-id", a.run_id,
                 "the run this node joins (default: the config's deployment.run_id); required");
  app.add_option("--assign-timeout", a.loop.assign_timeout,
                 "s to wait for an assignment (finite, > 0)");
  security::add_secret_options(
      app, a.security_dir, a.secret,
      "this node's folder from `rths pki init` (DIR/node_<id>); default: the "
      "config's deployment.security_dir",
      "any participant on the domain can then speak as the coordinator to this node");
}

// The arguments checked and completed from --config; the endpoint's options. Throws
// std::invalid_argument (or what the study's check throws) for bad input, before DDS starts.
transport::DdsEndpointOptions endpoint_options(NodeArgs& a) {
  if (a.node_id < 1) throw std::invalid_argument("--node-id must be >= 1");
  if (!(std::isfinite(a.loop.assign_timeout) && a.loop.assign_timeout > 0))  // NaN too
    throw std::invalid_argument(
        fmt::format("--assign-timeout {} s is not a time (finite, > 0)", a.loop.assign_timeout));
  if (a.domain < 0 && a.config_path.empty())
    throw std::invalid_argument("give --domain or --config");
  if (!a.config_path.empty()) {
    const config::Deployment deployment = checked_deployment(a.config_path);
    if (a.domain < 0) a.domain = deployment.domain_id();
    if (a.run_id.empty()) a.run_id = deployment.run_id();
    if (a.security_dir.empty() && !deployment.security_dir().empty())
      a.security_dir = security::node_dir(
          std::filesystem::path(a.config_path).parent_path() / deployment.security_dir(),
          a.node_id);
  }
  transport::DdsEndpointOptions options;
  if (!a.security_dir.empty())  // refused here, before the participant exists
    options.participant_properties =
        security::participant_properties(security::check_node_security(a.security_dir, a.node_id));
  a.secret.dds_security = !a.security_dir.empty();
  options.run_secret = security::resolve_run_secret(a.secret);
  if (a.run_id.empty())
    throw std::invalid_argument(
        "give --run-id (or deployment.run_id in --config): the coordinator accepts only "
        "announcements of its own run, and this node only that run's assignment");
  options.domain_id = static_cast<std::uint32_t>(a.domain);
  options.coordinator = false;
  options.node_id = a.node_id;
  return options;
}

}  // namespace

int node_main(int argc, char** argv, const std::string& program, const ServiceFactory& factory) {
  CLI::App app{program + ": an rths node; the coordinator assigns its part of the study"};
  NodeArgs a;
  add_node_options(app, a);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  transport::DdsEndpointOptions options;
  try {
    options = endpoint_options(a);
  } catch (const std::exception& e) {
    std::cerr << program << ": " << e.what() << "\n";
    return 2;
  }
  try {
    transport::DdsEndpoint endpoint(options);
    auto service = factory(a.node_id, a.run_id);
    service->set_unauthenticated_source([&endpoint] { return endpoint.unauthenticated_count(); });
    const int code = run_node(endpoint, *service, a.loop);
    const transport::Unauthenticated dropped = endpoint.unauthenticated();
    if (dropped.count > 0)
      spdlog::warn("{}: {} messages dropped unread as unauthenticated (no valid MAC); newest: {}",
                   service->label(), dropped.count, dropped.last);
    return code;
  } catch (const std::exception& e) {
    std::cerr << program << " (node " << a.node_id << "): " << e.what() << "\n";
    return 3;
  }
}

CLI::Validator finite_in(double min, double max) {
  return CLI::Validator(
      [min, max](const std::string& input) -> std::string {
        const auto number = core::parse_finite(input);
        if (!number) return fmt::format("'{}' is not a finite number", core::printable(input));
        if (*number < min || *number > max)
          return fmt::format("{:g} is outside [{:g}, {:g}]", *number, min, max);
        return "";
      },
      fmt::format("FLOAT in [{:g} - {:g}]", min, max));  // as CLI::Range says it
}

}  // namespace rths::runtime
