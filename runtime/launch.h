#pragma once
// Launching a distributed run on this machine: every node of the deployment and the coordinator
// as separate processes over Cyclone DDS, each logging to its own file.
//
//   launch_run: start the nodes (--node-id, --domain, --run-id), then the coordinator (--config,
//   --case, --run-id, --record, --domain); wait for the coordinator (timeout: kill it, exit 124);
//   give the nodes a few seconds to leave after its STOP, then kill any still running.
//   Processes are placed on CPUs as options.cpu_placement says (default: lockstep on one CPU).
// CYCLONEDDS_URI: when unset, set (for the children) to the loopback configuration below, the same
// settings as configs/dds_loopback.xml.

#include <filesystem>
#include <string>
#include <vector>

namespace rths::runtime {

// Inline Cyclone DDS configuration for one host (lo, no multicast, ParticipantIndex auto,
// MaxAutoParticipantIndex 32, Peer localhost).
extern const char* const kLoopbackDdsConfig;

// Sets CYCLONEDDS_URI to kLoopbackDdsConfig if it is unset. Returns the value in effect.
std::string ensure_dds_config();

// Where the launched processes run. A lockstep step is strictly sequential (coordinator ->
// nodes -> coordinator), so on one host it is fastest with every process on one CPU: no
// cross-CPU wake-ups (rths_runtime_bench on a 2-CPU VM, coordinator + substructure node +
// actuator emulator: 10,100-11,800 steps/s pinned, 7,900-10,300 spread). Real-time runs keep
// the scheduler's placement: the pacing sleep and the nodes' work should not queue behind each
// other on one CPU.
enum class CpuPlacement {
  kAuto,     // lockstep: one CPU (the highest allowed; unpinned with a warning if that fails);
             // real time: spread
  kOneCpu,   // always one CPU (failing to pin is an error)
  kSpread,   // never pin
};

struct LaunchOptions {
  std::filesystem::path config;
  std::string case_name;               // empty: the deployment's or the reference case
  std::string run_id;                  // empty: generated
  int domain = -1;                     // -1: the config's deployment.domain_id
  std::filesystem::path programs_dir;  // empty: found beside this executable / build tree / PATH
  std::filesystem::path record;        // run record to write
  std::filesystem::path log_dir;       // per-process logs
  double timeout = 0.0;                // s for the coordinator; 0 = none
  CpuPlacement cpu_placement = CpuPlacement::kAuto;
  // DDS Security: the `rths pki init` directory; each process gets --security DIR/node_<id>.
  // Empty: the config's deployment.security_dir (relative to the config), else off.
  std::filesystem::path security_dir;
};

struct LaunchResult {
  int coordinator_exit = -1;
  std::string run_id;
  std::vector<std::string> node_labels;
  std::vector<int> node_exits;          // 128 + signal when killed
  std::filesystem::path coordinator_log;
};

LaunchResult launch_run(const LaunchOptions& options);

}  // namespace rths::runtime
