// coordinator/program: a real-time run passes the platform gate before it joins DDS (refused:
// exit 3, naming the numbers and the fix), --accept-platform overrides it, and the record's header
// keeps the check and the override. The shared DDS domain, each test on topics of its own.
#include "coordinator/program.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "rt_check/probe.h"
#include "tests/runtime/test_support.h"
#include "tests/support/dds_scope.h"
#include "tests/support/real_time_run.h"
#include "tests/support/run_command_line.h"

namespace rths::coordinator {
namespace {

using ::testing::HasSubstr;

const char* kVerdict =
    "fail-safe window 2.93 ms (3 steps at 1024 Hz): does NOT hold\nto change:\n"
    "  - answer_window_ms: 9.00 command_watchdog_ms: 9.00 in the deployment\n";

std::filesystem::path refused_check(const std::filesystem::path& dir) {
  const auto path = dir / "platform.json";
  nlohmann::json platform{{"refused", true},
                          {"verdict", kVerdict},
                          {"window_ms", 2.93},
                          {"required_window_ms", 9.0},
                          {"lateness_max", 0.0035}};
  std::ofstream(path) << nlohmann::json{{"platform", platform}}.dump();
  return path;
}

std::string coordinator_command(const std::filesystem::path& config, const std::string& extra) {
  return test::program("rths-coordinator", "coordinator").string() + " --config " +
         config.string() + " " + extra;
}

TEST(PlatformGate, ARefusedCheckStopsARealTimeRunBeforeItStarts) {
  const auto dir = test::scratch_dir("gate_refused");
  const auto config = test::write_config(
      dir, test::paper_frame_study(
               0.2, "deployment { domain_id: " + std::to_string(test::scope_dds_to_this_test()) +
                        " clock: REAL_TIME }"));
  const auto record = dir / "run.rthsrec";
  const auto refused = test::run_command_line(coordinator_command(
      config, "--platform " + refused_check(dir).string() + " --record " + record.string()));
  EXPECT_EQ(refused.exit_code, 3) << refused.output;
  EXPECT_THAT(refused.output, HasSubstr("refusing to start"));
  EXPECT_THAT(refused.output, HasSubstr("answer_window_ms: 9.00"));
  EXPECT_THAT(refused.output, HasSubstr("--accept-platform"));
  EXPECT_FALSE(std::filesystem::exists(record));
  const auto unmeasured =
      test::run_command_line(coordinator_command(config, "--platform-seconds 0"));
  EXPECT_EQ(unmeasured.exit_code, 2) << unmeasured.output;
  EXPECT_THAT(unmeasured.output,
              HasSubstr("--platform-seconds 0 (not measured) needs --accept-platform"));
  const auto bad_window = test::write_config(
      dir, test::paper_frame_study(0.2,
                                   "deployment { clock: REAL_TIME answer_window_ms: 5 "
                                   "max_missed_answers: 5 }"));
  const auto both = test::run_command_line(coordinator_command(bad_window, "--platform-seconds 0"));
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_THAT(both.output,
              HasSubstr("deployment.answer_window_ms and deployment.max_missed_answers"));
}

TEST(PlatformGate, AcceptPlatformRunsAndTheRecordSaysSo) {
  const auto dir = test::scratch_dir("gate_accepted");
  runtime::LaunchOptions options;
  options.config = test::write_config(
      dir, test::paper_frame_study(0.3,
                                   "deployment { clock: REAL_TIME max_overrun_fraction: -1 "
                                   "answer_window_ms: 30 command_watchdog_ms: 30 }"));
  options.case_name = "reference";
  options.run_id = "gate_accepted";
  options.domain = test::scope_dds_to_this_test();
  options.programs_dir = RTHS_BINARY_DIR;
  options.record = dir / "run.rthsrec";
  options.log_dir = dir;
  options.timeout = 60;
  options.platform_file = refused_check(dir);
  options.accept_platform = true;
  test::StallWitness witness;
  const runtime::LaunchResult result = runtime::launch_run(options);
  const test::MeasuredPlatform machine = witness.finish();
  const runtime::RecordContents record = runtime::read_record(options.record);
  ASSERT_NE(record.header(), nullptr);
  const runtime::PlatformSummary& p = record.header()->platform();
  EXPECT_TRUE(p.refused());
  EXPECT_TRUE(p.accepted_override());
  EXPECT_EQ(p.verdict(), kVerdict);
  EXPECT_EQ(p.dma_latency_held(), rt_check::DmaLatencyHold().held());
  // The run's own verdict is judged by the suite's one rule (tests/support/real_time_run.h).
  if (const auto burned = test::loop_cpu_over_bound(test::read_file(result.coordinator_log)))
    FAIL() << *burned;
  if (result.coordinator_exit != 0 && record.footer() != nullptr)
    if (const auto why =
            test::machine_stalled(record.footer()->status(), *record.header(), machine))
      GTEST_SKIP() << *why;
  EXPECT_EQ(result.coordinator_exit, 0)
      << result.coordinator_log_tail << "\nthe machine meanwhile: " << machine.text;
}

}  // namespace
}  // namespace rths::coordinator
