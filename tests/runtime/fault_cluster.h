#pragma once
// What the fault tests on real processes over Cyclone DDS share (node_loss, coordinator_loss,
// start_up_faults, forged_control, forged_answers and record_disk_full tests): a cluster of node processes and a coordinator started for one study
// (start), how its processes trust each other (Trust), the record checks a failure's record
// must pass (expect_contiguous, expect_each_node_counted_unauthenticated), the real-time
// deployment whose fail-safes tolerate this shared machine (kRealTime), and tests/support's
// rths_rogue as a stranger (rogue, rogue_trials).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iostream>
#include <thread>

#include "rths/proto/runtime.pb.h"
#include "runtime/node/schema.h"
#include "security/run_secret.h"
#include "test_support.h"
#include "tests/support/platform_gate.h"
#include "tests/support/real_time_run.h"
#include "transport/dds_endpoint.h"

namespace rths::faults {

using namespace std::chrono_literals;

struct Cluster {
  std::filesystem::path dir, record;
  std::vector<util::ChildProcess> nodes;
  std::optional<util::ChildProcess> coordinator;
};

// How the processes of a cluster recognise each other: with a run secret (each process gets
// --secret-file of one made as `rths pki secret` makes it), or --insecure (the writer pinning
// alone, as before run secrets).
enum class Trust { kInsecure, kSecret };

// Arguments that hand a process the cluster's trust; makes the secret file in `dir` once.
inline std::vector<std::string> trust_arguments(Trust trust, const std::filesystem::path& dir) {
  if (trust == Trust::kInsecure) return {"--insecure"};
  const auto file = dir / "run.secret";
  if (!std::filesystem::exists(file))
    security::write_run_secret_file(file, security::generate_run_secret());
  return {"--secret-file", file.string()};
}

// Starts the listed nodes (id, kind) and the coordinator for `text` (started as
// `coordinator_options` says).
inline Cluster start(const std::string& name, const std::string& text, int domain,
                     const std::vector<std::pair<int, bool>>& nodes, const std::string& case_name,
                     const util::ChildOptions& coordinator_options = {},
                     Trust trust = Trust::kInsecure,
                     const std::function<void()>& before_coordinator = {}) {
  Cluster c;
  c.dir = test::scratch_dir(name);
  const auto config = test::write_config(c.dir, text);
  c.record = c.dir / "run.rthsrec";
  const std::vector<std::string> trusted = trust_arguments(trust, c.dir);
  for (const auto& [id, substructure] : nodes) {
    std::vector<std::string> args{
        "--node-id", std::to_string(id), "--domain", std::to_string(domain), "--run-id", name};
    args.insert(args.end(), trusted.begin(), trusted.end());
    c.nodes.emplace_back(substructure
                             ? test::program("rths-substructure-node", "substructure_nodes")
                             : test::program("rths-actuator-emulator", "actuator_emulator"),
                         args, c.dir / ("node_" + std::to_string(id) + ".log"));
  }
  std::vector<std::string> args{"--config",
                                config.string(),
                                "--run-id",
                                name,
                                "--domain",
                                std::to_string(domain),
                                "--record",
                                c.record.string(),
                                "--case",
                                case_name,
                                "--platform-seconds",
                                "0",
                                "--accept-platform"};
  args.insert(args.end(), trusted.begin(), trusted.end());
  if (before_coordinator) before_coordinator();
  c.coordinator.emplace(test::program("rths-coordinator", "coordinator"), args,
                        c.dir / "coordinator.log", coordinator_options);
  return c;
}

// Steps 0..n-1 with no gap, as a record cut at a failure must be.
inline void expect_contiguous(const runtime::RecordContents& record) {
  const auto steps = record.steps();
  for (std::size_t k = 0; k < steps.size(); ++k) ASSERT_EQ(steps[k]->step(), static_cast<long>(k));
}

// The fail-safe's step counts are widened from 3 to tolerate this shared, loaded test machine
// (a healthy node must not trip them); the mechanism is the same. Deadline misses are not what
// these tests judge.
inline const std::string kRealTime =
    "deployment { clock: REAL_TIME liveliness_timeout: 0.3 heartbeat_period: 0.02 "
    "max_missed_answers: 30 command_watchdog_periods: 30 max_overrun_fraction: -1 }";

// tests/support/rogue_participant.cpp in `domain` (it learns the run id off the wire).
inline util::ChildProcess rogue(const std::filesystem::path& log, int domain,
                                std::vector<std::string> attack) {
  std::vector<std::string> args{"--domain", std::to_string(domain), "--seconds", "60"};
  args.insert(args.end(), attack.begin(), attack.end());
  return util::ChildProcess(test::program("rths_rogue", "tests/support"), args, log);
}

// Trials per forgery (RTHS_ROGUE_TRIALS overrides; the README quotes a longer measurement).
inline int rogue_trials() {
  const char* env = std::getenv("RTHS_ROGUE_TRIALS");
  return env && *env ? std::max(1, std::atoi(env)) : 3;
}

// Each node's own unauthenticated drops as the record's footer and the coordinator's summary
// name them (its last heartbeat's, final on STOP): at least one, none counted not entitled.
inline void expect_each_node_counted_unauthenticated(const runtime::RunFooter& footer,
                                                     const std::string& summary) {
  ASSERT_EQ(footer.node_rejects_size(), 2);
  for (const runtime::NodeRejects& n : footer.node_rejects()) {
    EXPECT_TRUE(n.final()) << n.label();
    EXPECT_GT(n.rejected().unauthenticated(), 0u) << n.label();
    EXPECT_EQ(n.rejected().not_entitled(), 0u) << n.label();
    EXPECT_THAT(summary, testing::HasSubstr(n.label() + " DDS messages rejected: ")) << summary;
    EXPECT_THAT(summary, testing::HasSubstr(", unauthenticated " +
                                            std::to_string(n.rejected().unauthenticated()) + "\n"))
        << summary;
  }
}

}  // namespace rths::faults
