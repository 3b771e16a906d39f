#include "runtime/launch/launch.h"

#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "runtime/node/plan.h"
#include "runtime/node/schema.h"
#include "security/check.h"
#include "security/pki.h"
#include "security/run_secret.h"
#include "study/study.h"
#include "transport/transport.h"
#include "util/process.h"

namespace rths::runtime {

const char* const kLoopbackDdsConfig =
    "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/>"
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>32"
    "</MaxAutoParticipantIndex><Peers><Peer address=\"localhost\"/></Peers></Discovery>"
    "</Domain></CycloneDDS>";

std::string ensure_dds_config() {
  if (const char* uri = std::getenv("CYCLONEDDS_URI"); uri && *uri) return uri;
  setenv("CYCLONEDDS_URI", kLoopbackDdsConfig, 1);
  return kLoopbackDdsConfig;
}

std::string make_run_id(const std::string& label) {
  char host[128] = {};
  gethostname(host, sizeof host - 1);
  std::string id;
  for (char c : label) {
    const bool keep =
        std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
    id += keep ? c : '_';
  }
  if (!id.empty()) id += "-";
  return id + host + "-" + std::to_string(getpid()) + "-" +
         std::to_string(transport::realtime_ns());
}

namespace {

Placement local_placement(int /*node_id*/) {
  const char* uri = std::getenv("CYCLONEDDS_URI");
  return {{}, {{"CYCLONEDDS_URI", uri && *uri ? uri : kLoopbackDdsConfig}}, "this host"};
}

// What every process of one run gets: the DDS Security folder and the run secret.
struct Credentials {
  std::filesystem::path security_dir;
  std::string secret;  // handed down in the environment, never on the command line
};

// The program of a node of this kind; the controller node's is looked up only when a deployment
// has one, so a tree built without it still launches every other deployment.
std::filesystem::path node_program(const util::NodePrograms& programs, config::NodeSpec::Kind kind,
                                   const std::filesystem::path& programs_dir) {
  if (kind == config::NodeSpec::SUBSTRUCTURE) return programs.substructure;
  if (kind == config::NodeSpec::CONTROLLER)
    return util::find_program("rths-controller-node", "controller_node", programs_dir);
  return programs.actuator_emulator;
}

util::ChildProcess start(const std::filesystem::path& program, std::vector<std::string> args,
                         const Credentials& credentials, int node_id,
                         const std::filesystem::path& log, const std::string& label,
                         const PlacementStrategy& placement) {
  const auto security_args = security::security_arguments(credentials.security_dir, node_id);
  args.insert(args.end(), security_args.begin(), security_args.end());
  Placement where = placement(node_id);
  where.environment[security::kSecretEnv] = credentials.secret;
  std::vector<std::string> argv = where.prefix;
  argv.push_back(program.string());
  argv.insert(argv.end(), args.begin(), args.end());
  spdlog::debug("{} at {}: {}", label, where.where, util::command_line(argv));
  return util::ChildProcess(
      program, args, log,
      {label + " at " + where.where, std::move(where.prefix), std::move(where.environment)});
}

}  // namespace

bool on_one_cpu(CpuPlacement placement, const config::Deployment& deployment) {
  if (placement != CpuPlacement::kAuto) return placement == CpuPlacement::kOneCpu;
  return deployment.clock() != config::Deployment::REAL_TIME &&
         deployment.nodes_size() <= kOneCpuMaxNodes;
}

std::unique_ptr<util::ScopedCpuExclude> keep_off_loop_cpu(const config::Deployment& deployment) {
  if (deployment.clock() != config::Deployment::REAL_TIME || !deployment.pin_loop()) return nullptr;
  auto guard = std::make_unique<util::ScopedCpuExclude>(deployment.loop_cpu());
  if (!guard->active()) {
    spdlog::warn(
        "pin_loop: CPU {} cannot be kept for the loop alone (not allowed, or the only "
        "CPU); the nodes share it",
        deployment.loop_cpu());
    return nullptr;
  }
  return guard;
}

namespace {

std::filesystem::path security_dir_of(const LaunchOptions& options,
                                      const config::Deployment& deployment, int domain) {
  const std::filesystem::path dir = !options.security_dir.empty() ? options.security_dir
                                    : !deployment.security_dir().empty()
                                        ? options.config.parent_path() / deployment.security_dir()
                                        : std::filesystem::path();
  if (!dir.empty()) {  // every document checked before any process starts
    std::vector<int> ids{security::kCoordinatorNodeId};
    for (const config::NodeSpec& node : deployment.nodes()) ids.push_back(node.id());
    security::check_lab_security(dir, ids, domain);
  }
  return dir;
}

// Children inherit the mask of the thread that starts them, so the pin is released once they
// have started.
std::unique_ptr<util::ScopedCpuPin> pin_for_children(const LaunchOptions& options,
                                                     const config::Deployment& deployment) {
  if (!on_one_cpu(options.cpu_placement, deployment)) return nullptr;
  try {
    return std::make_unique<util::ScopedCpuPin>();
  } catch (const std::runtime_error& e) {
    if (options.cpu_placement == CpuPlacement::kOneCpu) throw;
    spdlog::warn("lockstep processes left unpinned: {}", e.what());  // only slower
    return nullptr;
  }
}

std::vector<std::string> coordinator_arguments(const LaunchOptions& options,
                                               const LaunchResult& result, int domain) {
  std::vector<std::string> args{"--config", options.config.string(), "--run-id", result.run_id,
                                "--domain", std::to_string(domain),  "--case",   result.case_name};
  if (!options.record.empty()) args.insert(args.end(), {"--record", options.record.string()});
  if (!options.platform_file.empty())
    args.insert(args.end(), {"--platform", options.platform_file.string()});
  if (options.platform_seconds >= 0)
    args.insert(args.end(), {"--platform-seconds", std::to_string(options.platform_seconds)});
  if (options.accept_platform) args.push_back("--accept-platform");
  args.insert(args.end(), options.coordinator_args.begin(), options.coordinator_args.end());
  return args;
}

// The coordinator's exit code; on a stop request or the timeout it is terminated and
// result.status says why (124 for a timeout).
int wait_for_coordinator(util::ChildProcess& coordinator, const LaunchOptions& options,
                         std::chrono::steady_clock::time_point started, LaunchResult& result) {
  const auto deadline =
      options.timeout > 0
          ? std::optional(started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                        std::chrono::duration<double>(options.timeout)))
          : std::nullopt;
  std::optional<int> exit_code;
  while (!(exit_code = coordinator.wait_for(std::chrono::milliseconds(20)))) {
    if (options.stop_requested && options.stop_requested()) {
      result.status = "interrupted";
      break;
    }
    if (deadline && std::chrono::steady_clock::now() > *deadline) {
      std::ostringstream why;
      why << "timed out after " << options.timeout << " s";
      result.status = why.str();
      break;
    }
  }
  if (exit_code) return *exit_code;
  coordinator.terminate();
  return result.status == "interrupted" ? coordinator.wait() : 124;
}

// After an orderly end the nodes got STOP and leave by themselves; otherwise do not wait long.
void reap_nodes(std::vector<util::ChildProcess>& nodes, LaunchResult& result) {
  const auto grace = std::chrono::steady_clock::now() +
                     (result.status.empty() ? std::chrono::milliseconds(kNodeExitGrace)
                                            : std::chrono::milliseconds(1000));
  for (util::ChildProcess& node : nodes) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        grace - std::chrono::steady_clock::now());
    if (!node.wait_for(std::max(left, std::chrono::milliseconds(0))))
      spdlog::warn("{} did not exit after the coordinator; stopping it", node.name());
    result.node_exits.push_back(node.terminate());
  }
}

}  // namespace

LaunchResult launch_run(const LaunchOptions& options) {
  const config::Study study = study::load_study(options.config);
  const study::PreparedStudy prepared = study::prepare_study(study, options.config.parent_path());
  check_deployment(prepared);  // as `rths run` checks it; then the case's own plan below
  const config::Case& study_case = study::find_case(
      study, options.case_name.empty() ? study.deployment().case_name() : options.case_name);
  const core::HybridSetup setup = study::setup_for_case(prepared, study_case);
  const config::Deployment deployment = with_default_nodes(study.deployment(), setup);
  make_plan(setup, deployment);  // refuse a bad deployment before starting anything

  LaunchResult result;
  result.case_name = study_case.name();
  result.run_id =
      options.run_id.empty() ? make_run_id(study.name() + "-" + result.case_name) : options.run_id;
  const int domain = options.domain >= 0 ? options.domain : deployment.domain_id();
  // A fresh secret per run: only the processes started here learn it.
  const Credentials credentials{security_dir_of(options, deployment, domain),
                                security::generate_run_secret()};
  const util::NodePrograms programs = util::find_node_programs(options.programs_dir);
  const PlacementStrategy placement = options.placement ? options.placement : local_placement;
  std::filesystem::create_directories(options.log_dir);

  std::unique_ptr<util::ScopedCpuPin> pin = pin_for_children(options, deployment);
  auto off_loop_cpu = keep_off_loop_cpu(deployment);
  const auto started = std::chrono::steady_clock::now();
  std::vector<util::ChildProcess> nodes;
  for (const config::NodeSpec& node : deployment.nodes()) {
    const std::string id = std::to_string(node.id());
    const std::string label = "node " + id + " (" + node_kind_name(node.kind()) + ")";
    result.node_labels.push_back(label);
    result.node_ids.push_back(node.id());
    nodes.push_back(
        start(node_program(programs, node.kind(), options.programs_dir),
              {"--node-id", id, "--domain", std::to_string(domain), "--run-id", result.run_id},
              credentials, node.id(), options.log_dir / ("node_" + id + ".log"), label, placement));
  }
  result.coordinator_log = options.log_dir / "coordinator.log";
  util::ChildProcess coordinator =
      start(programs.coordinator, coordinator_arguments(options, result, domain), credentials,
            security::kCoordinatorNodeId, result.coordinator_log, "coordinator", placement);
  pin.reset();
  off_loop_cpu.reset();

  result.coordinator_exit = wait_for_coordinator(coordinator, options, started, result);
  reap_nodes(nodes, result);
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.coordinator_log_tail = coordinator.log_tail(1500);
  return result;
}

}  // namespace rths::runtime
