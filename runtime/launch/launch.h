#pragma once
// The one launch sequence of a distributed run, for `rths launch` (every process on this host)
// and `rths sites` (each process in its site's network namespace):
//
//   launch_run: load the study and refuse a bad deployment before starting anything; check every
//   DDS Security document, and that the governance covers the run's domain; make a fresh run
//   secret (security/run_secret.h) and hand it to every process it starts in its environment
//   (RTHS_RUN_SECRET; never on a command line, on DDS or in a log); start the nodes
//   (--node-id, --domain, --run-id), then the coordinator
//   (--config, --case, --run-id, --record, --domain), each where options.placement puts it, with
//   its log in log_dir (node_<id>.log, coordinator.log); wait for the coordinator until it exits,
//   options.timeout passes (status "timed out after T s", exit 124) or options.stop_requested()
//   says so (status "interrupted"); then give the nodes kNodeExitGrace to leave after the STOP
//   (1 s after a timeout or interruption), and terminate any still running.
//   Processes are placed on CPUs as options.cpu_placement says (default: lockstep on one CPU).
//
// Where a process runs is a strategy (Placement): local by default (CYCLONEDDS_URI = the loopback
// configuration below, unless the caller's environment sets it), or a site's namespace (prefix
// `ip netns exec ...`, its own DDS configuration).
// Run ids: one format, make_run_id().

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rths/proto/deployment.pb.h"
#include "util/process.h"

namespace rths::runtime {

// Inline Cyclone DDS configuration for one host (lo, no multicast, ParticipantIndex auto,
// MaxAutoParticipantIndex 32, Peer localhost).
extern const char* const kLoopbackDdsConfig;

// Sets CYCLONEDDS_URI to kLoopbackDdsConfig if it is unset. Returns the value in effect.
std::string ensure_dds_config();

// "<label>-<host>-<pid>-<CLOCK_REALTIME ns>", label = "<study>-<case>" for launch and sites
// (characters other than [A-Za-z0-9_.-] become '_'); an empty label drops its part.
std::string make_run_id(const std::string& label = "");

// Where the launched processes run. A lockstep step is strictly sequential (coordinator ->
// nodes -> coordinator): with up to three nodes it is about as fast on one CPU as spread,
// without cross-CPU wake-ups; with more, their answers are computed in parallel only when
// spread, and one CPU serves them one after another (README "Nodes and the step's cost" has
// rths_runtime_bench --scaling's figures). Real-time runs keep the scheduler's placement: the
// pacing sleep and the nodes' work should not queue behind each other on one CPU.
inline constexpr int kOneCpuMaxNodes = 3;
enum class CpuPlacement {
  kAuto,    // lockstep with at most kOneCpuMaxNodes nodes: one CPU (the highest allowed;
            // unpinned with a warning if that fails); otherwise spread
  kOneCpu,  // always one CPU (failing to pin is an error)
  kSpread,  // never pin
};
// Whether the launched processes share one CPU: `deployment` with its nodes (default ones added).
bool on_one_cpu(CpuPlacement placement, const config::Deployment& deployment);

// Where one process (node id; 0 = the coordinator) runs: a command prefix and environment
// overrides, and a label for messages ("site lab").
struct Placement {
  std::vector<std::string> prefix;
  std::map<std::string, std::string> environment;
  std::string where;
};
using PlacementStrategy = std::function<Placement(int node_id)>;

inline constexpr std::chrono::seconds kNodeExitGrace{5};  // after the coordinator, for STOP

struct LaunchOptions {
  std::filesystem::path config;
  std::string case_name;               // empty: the deployment's or the reference case
  std::string run_id;                  // empty: make_run_id("<study>-<case>")
  int domain = -1;                     // -1: the config's deployment.domain_id
  std::filesystem::path programs_dir;  // empty: find_node_programs' search
  std::filesystem::path record;        // run record to write
  std::filesystem::path log_dir;       // per-process logs
  double timeout = 0.0;                // s for the coordinator; 0 = none
  CpuPlacement cpu_placement = CpuPlacement::kAuto;
  // DDS Security: the `rths pki init` directory; each process gets --security DIR/node_<id>.
  // Empty: the config's deployment.security_dir (relative to the config), else off.
  std::filesystem::path security_dir;
  PlacementStrategy placement;           // empty: local (loopback DDS unless CYCLONEDDS_URI is set)
  std::function<bool()> stop_requested;  // polled every 20 ms; true = stop now
  // Real time: the coordinator's platform check (coordinator/program.h): a check already made
  // (`rths rt-check --json` output), else seconds of measurement (< 0: the coordinator's
  // default); accept_platform runs a deployment the check refuses (the record says so).
  std::filesystem::path platform_file;
  double platform_seconds = -1.0;
  bool accept_platform = false;
  std::vector<std::string> coordinator_args;  // appended to the coordinator's (e.g. --view H:P)
};

struct LaunchResult {
  int coordinator_exit = -1;  // 124 when the timeout stopped it
  std::string status;         // empty, "interrupted" or "timed out after T s"
  std::string run_id;
  std::string case_name;  // the case that ran
  std::vector<std::string> node_labels;
  std::vector<int> node_ids;
  std::vector<int> node_exits;  // 128 + signal when a signal ended it
  std::filesystem::path coordinator_log;
  std::string coordinator_log_tail;  // the last 1500 bytes, for messages
  double wall_seconds = 0.0;         // start of the first process to the last one's exit
};

// A real-time deployment with pin_loop gives loop_cpu to the coordinator's loop thread alone: the
// processes started while the returned guard lives (the nodes, the coordinator) start on the
// other CPUs; the coordinator then moves its loop thread onto loop_cpu. Null otherwise, and when
// the machine has no other CPU.
std::unique_ptr<util::ScopedCpuExclude> keep_off_loop_cpu(const config::Deployment& deployment);

// Throws std::invalid_argument for a bad config or deployment (before anything starts),
// std::runtime_error for a program that cannot be found or started.
LaunchResult launch_run(const LaunchOptions& options);

}  // namespace rths::runtime
