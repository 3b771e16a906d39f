#include "runtime/launch.h"

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "core/study.h"
#include "runtime/plan.h"
#include "runtime/process.h"
#include "runtime/schema.h"
#include "security/check.h"
#include "security/pki.h"
#include "transport/transport.h"

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

LaunchResult launch_run(const LaunchOptions& options) {
  const config::Study study = core::load_study(options.config);
  const core::PreparedStudy prepared =
      core::prepare_study(study, options.config.parent_path());
  const std::string case_name =
      options.case_name.empty() ? study.deployment().case_name() : options.case_name;
  const core::HybridSetup setup = core::setup_for_case(prepared, find_case(study, case_name));
  const config::Deployment deployment = with_default_nodes(study.deployment(), setup);
  make_plan(setup, deployment);  // refuse a bad deployment before starting anything

  LaunchResult result;
  result.run_id = options.run_id.empty()
                      ? "launch-" + std::to_string(transport::realtime_ns())
                      : options.run_id;
  const int domain = options.domain >= 0 ? options.domain : deployment.domain_id();
  const std::filesystem::path security_dir =
      !options.security_dir.empty()        ? options.security_dir
      : !deployment.security_dir().empty() ? options.config.parent_path() / deployment.security_dir()
                                           : std::filesystem::path();
  if (!security_dir.empty()) {  // every document checked before any process starts
    std::vector<int> ids{security::kCoordinatorNodeId};
    for (const config::NodeSpec& node : deployment.nodes()) ids.push_back(node.id());
    security::check_lab_security(security_dir, ids);
  }
  ensure_dds_config();
  std::filesystem::create_directories(options.log_dir);

  const auto coordinator_program =
      find_program("rths-coordinator", "coordinator", options.programs_dir);
  const auto substructure_program =
      find_program("rths-substructure-node", "substructure_nodes", options.programs_dir);
  const auto emulator_program =
      find_program("rths-actuator-emulator", "actuator_emulator", options.programs_dir);

  // Children inherit the mask of the thread that forks them; restored before waiting.
  const bool one_cpu =
      options.cpu_placement == CpuPlacement::kOneCpu ||
      (options.cpu_placement == CpuPlacement::kAuto &&
       deployment.clock() != config::Deployment::REAL_TIME);
  std::unique_ptr<ScopedCpuPin> pin;
  if (one_cpu) {
    try {
      pin = std::make_unique<ScopedCpuPin>();
    } catch (const std::runtime_error& e) {
      if (options.cpu_placement == CpuPlacement::kOneCpu) throw;
      spdlog::warn("lockstep processes left unpinned: {}", e.what());  // only slower
    }
  }
  std::vector<ChildProcess> nodes;
  for (const config::NodeSpec& node : deployment.nodes()) {
    const bool sub = node.kind() == config::NodeSpec::SUBSTRUCTURE;
    const std::string id = std::to_string(node.id());
    result.node_labels.push_back("node " + id + " (" + node_kind_name(node.kind()) + ")");
    std::vector<std::string> node_args{"--node-id", id, "--domain", std::to_string(domain),
                                       "--run-id", result.run_id};
    const auto security_args = security::security_arguments(security_dir, node.id());
    node_args.insert(node_args.end(), security_args.begin(), security_args.end());
    nodes.emplace_back(sub ? substructure_program : emulator_program, node_args,
                       options.log_dir / ("node_" + id + ".log"));
  }
  std::vector<std::string> args{"--config", options.config.string(), "--run-id", result.run_id,
                                "--domain", std::to_string(domain)};
  if (!case_name.empty()) args.insert(args.end(), {"--case", case_name});
  if (!options.record.empty()) args.insert(args.end(), {"--record", options.record.string()});
  const auto security_args = security::security_arguments(security_dir, security::kCoordinatorNodeId);
  args.insert(args.end(), security_args.begin(), security_args.end());
  result.coordinator_log = options.log_dir / "coordinator.log";
  ChildProcess coordinator(coordinator_program, args, result.coordinator_log);
  pin.reset();
  if (options.timeout > 0) {
    const auto code = coordinator.wait_for(
        std::chrono::milliseconds(static_cast<long long>(options.timeout * 1000)));
    if (code) {
      result.coordinator_exit = *code;
    } else {
      coordinator.signal(SIGKILL);
      coordinator.wait();
      result.coordinator_exit = 124;
    }
  } else {
    result.coordinator_exit = coordinator.wait();
  }
  // Nodes leave on STOP; those that do not within a few seconds are killed.
  const auto grace = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  for (ChildProcess& node : nodes) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        grace - std::chrono::steady_clock::now());
    auto code = node.wait_for(std::max(left, std::chrono::milliseconds(0)));
    if (!code) {
      node.signal(SIGKILL);
      code = node.wait();
    }
    result.node_exits.push_back(*code);
  }
  return result;
}

}  // namespace rths::runtime
