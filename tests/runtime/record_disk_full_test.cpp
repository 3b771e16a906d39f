// A disk that fills up under the run record of a real-time run on real processes over Cyclone DDS
// (the shared domain, on topics of its own): the run stops within five steps and the record reads
// up to there.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fault_cluster.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

using util::ChildProcess;
using namespace std::chrono_literals;
using namespace faults;

// The disk fills up under the record of a real-time run: the coordinator's file size is limited
// (prlimit's RLIMIT_FSIZE, as `ulimit -f` would; the coordinator ignores SIGXFSZ itself, so a
// write past it fails with EFBIG as a full disk fails with ENOSPC; no root or mount needed). The
// run stops within 5 steps of the last entry the disk took, holds and stops the nodes, names the
// reason, and the record reads up to there.
TEST(Faults, ARecordThatCannotBeWrittenStopsTheRunWithinFiveSteps) {
  if (!util::tool_available("prlimit")) GTEST_SKIP() << "prlimit (util-linux) is not installed";
  runtime::ensure_dds_config();
  // About 1000 steps of this run's entries (header ~1.3 KB, a step ~190 bytes with two links).
  constexpr std::uintmax_t kLimit = 200'000;
  util::ChildOptions limited;
  limited.prefix = {"sh", "-c",
                    "exec prlimit --fsize=" + std::to_string(kLimit) + " \"$0\" \"$@\""};
  // The nodes' own fail-safes are widened far beyond this loaded machine's stalls: the record is
  // what this test judges, and only the record may stop the run.
  const std::string text = test::paper_frame_study(
      8,
      "deployment { clock: REAL_TIME liveliness_timeout: 5 heartbeat_period: 0.02 "
      "max_missed_answers: 5000 command_watchdog_periods: 5000 max_overrun_fraction: -1 }");
  Cluster c = start("disk_full", text, test::scope_dds_to_this_test(), {{1, true}, {2, false}},
                    "lag_shift_14ms", limited);
  const auto code = c.coordinator->wait_for(20s);
  ASSERT_TRUE(code.has_value()) << "coordinator did not stop";
  const std::string log = test::read_file(c.dir / "coordinator.log");
  EXPECT_EQ(*code, 3) << "the machine's fault, not the test's: " << log;
  EXPECT_NE(log.find("cannot write run record " + c.record.string() + ": " + std::strerror(EFBIG)),
            std::string::npos)
      << log;
  EXPECT_EQ(std::filesystem::file_size(c.record), kLimit);
  const auto record = runtime::read_record(c.record);
  EXPECT_TRUE(record.truncated);
  EXPECT_FALSE(record.lost_entries()) << record.warning;
  EXPECT_EQ(record.footer(), nullptr);  // the disk took nothing after the failure
  expect_contiguous(record);
  const auto steps = static_cast<long>(record.steps().size());
  EXPECT_GT(steps, 500);
  EXPECT_LT(steps, 2000);
  const std::string marker = "stopped at step ";
  const auto at = log.find(marker);
  ASSERT_NE(at, std::string::npos) << log;
  const long stopped = std::stol(log.substr(at + marker.size()));
  std::cout << "record full at step " << steps - 1 << " (" << record.entries.size()
            << " entries); the coordinator stopped at step " << stopped << "\n";
  EXPECT_GE(stopped, steps - 1);
  EXPECT_LE(stopped - (steps - 1), 5);
  EXPECT_NE(log.find("HOLD sent to the actuator emulators"), std::string::npos) << log;
  for (auto& node : c.nodes) EXPECT_EQ(node.wait_for(5s).value_or(-1), 0) << node.name();
  EXPECT_NE(test::read_file(c.dir / "node_2.log").find("HOLD"), std::string::npos);
}

}  // namespace
}  // namespace rths
