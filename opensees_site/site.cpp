#include "opensees_site/site.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <vector>

#include "opensees_site/session.h"
#include "runtime/launch/launch.h"
#include "runtime/node/plan.h"
#include "security/check.h"
#include "security/pki.h"
#include "study/study.h"
#include "transport/dds_endpoint.h"
#include "util/process.h"

namespace rths::opensees {

struct Site::Prepared {
  study::PreparedStudy prepared;
  core::HybridSetup setup;
  config::Deployment deployment;
  std::string case_name;
  std::unique_ptr<BasicMapping> mapping;
  std::filesystem::path security_dir;
  std::string run_secret;  // resolved at construction when the emulators run elsewhere
};

namespace {

using std::chrono::duration_cast;
using std::chrono::nanoseconds;
using Seconds = std::chrono::duration<double>;

void require_site_study(const core::HybridSetup& setup, const config::Deployment& deployment,
                        const std::string& case_name) {
  if (!setup.partition.elements.empty())
    throw std::invalid_argument("opensees-site: case '" + case_name +
                                "' has experimental elements between DOFs; the site maps one "
                                "actuator per storey of a shear building");
  for (std::size_t s = 0; s < setup.partition.numerical.size(); ++s)
    if (setup.partition.numerical[s])
      throw std::invalid_argument(
          "opensees-site: storey " + std::to_string(s + 1) + " of case '" + case_name +
          "' has a numerical part; the OpenSees model holds the numerical structure, so every "
          "storey of the site's study is experimental (substructuring { experimental_fraction: 1 "
          "})");
  if (!core::is_explicit(setup.integrator))
    throw std::invalid_argument("opensees-site: integrator " + core::to_string(setup.integrator) +
                                " is implicit; the site's study needs an explicit one (it only "
                                "checks dt and stamps the steps; OpenSees integrates)");
  for (const config::NodeSpec& node : deployment.nodes())
    if (node.kind() != config::NodeSpec::ACTUATOR_EMULATOR)
      throw std::invalid_argument("opensees-site: deployment node " + std::to_string(node.id()) +
                                  " is not an ACTUATOR_EMULATOR; an OpenSees site drives only "
                                  "actuator emulators");
}

std::vector<util::ChildProcess> start_nodes(const config::Deployment& deployment,
                                            const SiteOptions& options,
                                            const std::filesystem::path& security_dir, int domain,
                                            const std::string& run_id, const std::string& secret) {
  const std::filesystem::path emulator =
      util::find_program("rths-actuator-emulator", "actuator_emulator", options.programs_dir);
  if (!options.log_dir.empty()) std::filesystem::create_directories(options.log_dir);
  std::vector<util::ChildProcess> nodes;
  for (const config::NodeSpec& node : deployment.nodes()) {
    const std::string id = std::to_string(node.id());
    std::vector<std::string> args{"--node-id", id,    "--domain", std::to_string(domain),
                                  "--run-id",  run_id};
    const auto security = security::security_arguments(security_dir, node.id());
    args.insert(args.end(), security.begin(), security.end());
    const auto log = options.log_dir.empty() ? std::filesystem::path("/dev/null")
                                             : options.log_dir / ("node_" + id + ".log");
    nodes.emplace_back(
        emulator, args, log,
        util::ChildOptions{
            "node " + id + " (actuator emulator)", {}, {{security::kSecretEnv, secret}}});
  }
  return nodes;
}

void stop_nodes(std::vector<util::ChildProcess>& nodes) {
  const auto grace = std::chrono::steady_clock::now() + runtime::kNodeExitGrace;
  for (util::ChildProcess& node : nodes) {
    const auto left =
        duration_cast<std::chrono::milliseconds>(grace - std::chrono::steady_clock::now());
    if (!node.wait_for(std::max(left, std::chrono::milliseconds(0))))
      spdlog::warn("{} did not exit after the run; stopping it", node.name());
    node.terminate();
  }
}

// The size message within `timeout`; the refusal's reason otherwise (empty when accepted).
std::string read_size_message(Connection& client, int basic_dofs, int expected_frame,
                              double timeout, int& frame_size) {
  SizeMessage sizes{};
  const auto r =
      client.read_exact(sizes.data(), sizeof sizes, duration_cast<nanoseconds>(Seconds(timeout)));
  if (r.status != Connection::Read::kComplete)
    return "size message incomplete: " + std::to_string(r.bytes) + " of " +
           std::to_string(sizeof sizes) + " bytes (11 ints), then " +
           (r.status == Connection::Read::kTimedOut
                ? "nothing for " + std::to_string(timeout) + " s"
                : std::string("the connection closed"));
  try {
    frame_size = check_size_message(sizes, basic_dofs, expected_frame);
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

Site::Site(SiteOptions options)
    : prepared_(std::make_unique<Prepared>()), options_(std::move(options)) {
  Prepared& p = *prepared_;
  const config::Study study = study::load_study(options_.config);
  p.prepared = study::prepare_study(study, options_.config.parent_path());
  // OpenSees' `analyze N dt` over an N-sample record ends at t = N dt, one step past the record's
  // last sample, where its Path time series gives 0: the site's motion has that sample too.
  p.prepared.motion.acceleration.push_back(0.0);
  const config::Case& study_case = study::find_case(
      study, options_.case_name.empty() ? study.deployment().case_name() : options_.case_name);
  p.case_name = study_case.name();
  p.setup = study::setup_for_case(p.prepared, study_case);
  p.deployment = runtime::with_default_nodes(study.deployment(), p.setup);
  require_site_study(p.setup, p.deployment, p.case_name);
  runtime::check_node_stages(runtime::make_plan(p.setup, p.deployment), p.setup.dt,
                             p.prepared.base_dir);
  std::vector<double> stiffness;
  for (int storey : p.setup.partition.actuator_storeys)
    stiffness.push_back(
        p.setup.partition.experimental[static_cast<std::size_t>(storey)]->initial_stiffness());
  p.mapping = std::make_unique<BasicMapping>(
      p.deployment.opensees(), stiffness, p.setup.partition.actuator_storeys, p.setup.model.dofs());
  p.security_dir = !options_.security_dir.empty() ? options_.security_dir
                   : !p.deployment.security_dir().empty()
                       ? options_.config.parent_path() / p.deployment.security_dir()
                       : std::filesystem::path();
  // Refused here, before any client is waited for: with start_nodes a fresh one is made per run.
  security::SecretChoice secret = options_.secret;
  secret.dds_security = !p.security_dir.empty();
  if (!options_.start_nodes) p.run_secret = security::resolve_run_secret(secret);
  if (p.security_dir.empty()) return;
  std::vector<int> ids{security::kCoordinatorNodeId};
  for (const config::NodeSpec& node : p.deployment.nodes()) ids.push_back(node.id());
  security::check_lab_security(p.security_dir, ids);
}

Site::~Site() = default;

int Site::basic_dofs() const { return prepared_->mapping->basic_dofs(); }

coordinator::RunOutcome Site::run_session(Connection& client, int frame_size,
                                          const transport::DdsEndpointOptions& dds,
                                          coordinator::CoordinatorOptions options,
                                          std::string& ending) {
  const Prepared& p = *prepared_;
  const bool real_time = p.deployment.clock() == config::Deployment::REAL_TIME;
  SessionOptions so;
  so.dt = p.setup.dt;
  so.max_steps = p.prepared.motion.acceleration.size();
  so.dofs = p.setup.model.dofs();
  so.frame_size = frame_size;
  so.first_frame_timeout =
      duration_cast<nanoseconds>(Seconds(runtime::start_timeout(p.deployment)));
  const double watchdog = runtime::command_watchdog_periods(p.deployment, p.setup.dt) * p.setup.dt;
  const double frame_timeout = real_time ? watchdog : runtime::step_timeout(p.deployment);
  so.frame_timeout = duration_cast<nanoseconds>(Seconds(frame_timeout));
  so.frame_timeout_reason = real_time ? "the emulator's watchdog (its window in steps x dt = " +
                                            std::to_string(watchdog) + " s)"
                                      : "step_timeout (" + std::to_string(frame_timeout) + " s)";
  so.divergence_bound = options.divergence_bound;
  so.client = "OpenSees client " + client.peer();
  Session session(client, *p.mapping, so);
  options.driver = [&session](core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                              core::SimulationResult& result) {
    session.drive(evaluator, hooks, result);
  };
  transport::DdsEndpoint endpoint(dds);
  coordinator::Coordinator coordinator(p.prepared, endpoint, std::move(options));
  coordinator::RunOutcome outcome = coordinator.run();
  ending = session.ending();
  return outcome;
}

SiteOutcome Site::serve(Listener& listener) {
  Prepared& p = *prepared_;
  SiteOutcome outcome;
  spdlog::info("waiting for an OpenSees genericClient on {}:{}", listener.address(),
               listener.port());
  std::optional<Connection> client = listener.accept(options_.accept_timeout);
  if (!client)
    throw std::runtime_error("no OpenSees client connected to " + listener.address() + ":" +
                             std::to_string(listener.port()) + " within " +
                             std::to_string(options_.accept_timeout.count() / 1000.0) + " s");
  outcome.client = client->peer();
  int frame_size = 0;
  outcome.refusal =
      read_size_message(*client, p.mapping->basic_dofs(), p.deployment.opensees().frame_size(),
                        runtime::start_timeout(p.deployment), frame_size);
  if (!outcome.refusal.empty()) {
    spdlog::error("refused the OpenSees client {}: {}; nothing was started", outcome.client,
                  outcome.refusal);
    return outcome;
  }
  spdlog::info("OpenSees client {}: {} basic DOFs, frames of {} doubles", outcome.client,
               p.mapping->basic_dofs(), frame_size);
  runtime::ensure_dds_config();
  const int domain = options_.domain >= 0 ? options_.domain : p.deployment.domain_id();
  coordinator::CoordinatorOptions co;
  co.run_id = !options_.run_id.empty() ? options_.run_id
              : !p.deployment.run_id().empty()
                  ? p.deployment.run_id()
                  : runtime::make_run_id(p.prepared.config.name() + "-" + p.case_name);
  co.case_name = p.case_name;
  co.record = options_.record;
  std::vector<util::ChildProcess> nodes;
  transport::DdsEndpointOptions dds;
  dds.run_secret = options_.start_nodes ? security::generate_run_secret() : p.run_secret;
  if (options_.start_nodes)
    nodes = start_nodes(p.deployment, options_, p.security_dir, domain, co.run_id, dds.run_secret);
  dds.domain_id = static_cast<std::uint32_t>(domain);
  if (!p.security_dir.empty())
    dds.participant_properties = security::participant_properties(security::check_node_security(
        security::node_dir(p.security_dir, security::kCoordinatorNodeId),
        security::kCoordinatorNodeId));
  outcome.run = run_session(*client, frame_size, dds, std::move(co), outcome.ending);
  outcome.served = true;
  client.reset();  // OpenSees sees the close at once
  stop_nodes(nodes);
  return outcome;
}

}  // namespace rths::opensees
