#pragma once
// Set-up shared by the benchmarks' distributed runs (benchmarks print figures; never tests): the
// benchmarks' SDOF study as text, and one run's directory, node processes and coordinator.
//
// sdof_study_text(name, dt, motion, deployment): T = 0.5 s, m = 1000 kg, zeta = 5 %, a third of
//   the stiffness experimental (linear), explicit Newmark at dt (s, printed with 17 digits so
//   1/1024 stays exact), the `motion` block, one case "lag" (a 14 ms shift), then `deployment`
//   verbatim. imperial_valley_motion(seconds): the shared Imperial Valley record (the AT2 file at
//   imperial_valley_path()) cut to
//   `seconds` (s), as a motion block.
// DistributedRun(spec): in TMP/<spec.directory>, writes study.textproto (the text) and starts the
//   node processes: substructure nodes with ids 1..s, then the emulators (ids from 2 when there
//   is no substructure node, as the studies' deployments name them), each with --node-id,
//   --domain and --run-id, logging to node_<id>.log. With keep_off_loop_cpu the nodes start off
//   the loop CPU as `rths launch` starts them (runtime::keep_off_loop_cpu), until destruction.
//   start(options): the coordinator in this process over DDS on the domain (loopback), recording
//   to run.rthsrec with the spec's run id; the caller runs it. prepared(): the study as start()
//   prepares it. wait_for_nodes(): up to 5 s each.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "coordinator/coordinator.h"
#include "runtime/launch/launch.h"
#include "transport/dds_endpoint.h"
#include "util/process.h"

namespace rths::bench {

std::string imperial_valley_path();  // the shared AT2 file
std::string imperial_valley_motion(double seconds);
std::string sdof_study_text(const std::string& name, double dt, const std::string& motion,
                            const std::string& deployment);

struct NodeSet {
  int substructures = 1, emulators = 1;
};

struct RunSpec {
  std::string directory;  // under the temporary directory
  std::string run_id;
  std::string study_text;
  int domain = 0;
  NodeSet nodes;
  bool keep_off_loop_cpu = false;
  // false: no run secret (the nodes started --insecure, no MAC on any message), to measure the
  // MAC's cost against the same run with it.
  bool run_secret = true;
};

class DistributedRun {
 public:
  explicit DistributedRun(const RunSpec& spec);
  const std::filesystem::path& dir() const { return dir_; }
  const std::filesystem::path& record() const { return record_; }
  const config::Study& study() const { return study_; }
  // The study prepared as start() prepares it (for what must know the run before it starts).
  study::PreparedStudy prepared() const;
  coordinator::Coordinator& start(coordinator::CoordinatorOptions options);
  void wait_for_nodes();

 private:
  std::filesystem::path dir_, record_;
  std::string run_id_;
  std::string secret_;  // the run secret the nodes get in their environment
  int domain_;
  config::Study study_;
  std::unique_ptr<util::ScopedCpuExclude> off_loop_cpu_;
  std::vector<util::ChildProcess> nodes_;
  std::unique_ptr<transport::DdsEndpoint> endpoint_;
  std::unique_ptr<coordinator::Coordinator> coordinator_;
};

}  // namespace rths::bench
