#pragma once
// Launching a distributed run on this machine: every node of the deployment and the coordinator
// as separate processes over Cyclone DDS, each logging to its own file.
//
//   launch_run: start the nodes (--node-id, --domain, --run-id), then the coordinator (--config,
//   --case, --run-id, --record, --domain); wait for the coordinator (timeout: kill it, exit 124);
//   give the nodes a few seconds to leave after its STOP, then kill any still running.
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

struct LaunchOptions {
  std::filesystem::path config;
  std::string case_name;               // empty: the deployment's or the reference case
  std::string run_id;                  // empty: generated
  int domain = -1;                     // -1: the config's deployment.domain_id
  std::filesystem::path programs_dir;  // empty: found beside this executable / build tree / PATH
  std::filesystem::path record;        // run record to write
  std::filesystem::path log_dir;       // per-process logs
  double timeout = 0.0;                // s for the coordinator; 0 = none
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
