// `rths rt-check`: the report's JSON shape, the verdict's exit code and its bad input, run as a
// user would (short measurements: figures are not judged here).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/support/run_command_line.h"

namespace {

using ::testing::HasSubstr;

const std::string kRths = RTHS_EXECUTABLE;

TEST(RtCheck, JsonHasThePlatformTheVerdictAndTheFixes) {
  // Either verdict (a stall in the 0.3 s can fail it); a failed one adds its line on stderr after
  // the JSON, which the output here also holds.
  const auto r = rths::test::run_command_line(kRths + " rt-check --seconds 0.3 --rate 100 --json");
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  const std::size_t open = r.output.find('{'), close = r.output.rfind('}');
  ASSERT_TRUE(open != std::string::npos && close != std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(r.output.substr(open, close - open + 1), nullptr, false);
  ASSERT_FALSE(j.is_discarded()) << r.output;
  for (const char* key :
       {"preemption", "governor", "isolated_cpus", "irq_affinity", "memlock_limit_bytes",
        "rtprio_limit", "dma_latency_holdable", "measured_cpus", "lateness_median", "lateness_p99",
        "lateness_p9999", "lateness_max", "stalls_over_1ms_per_minute",
        "stalls_over_2ms_per_minute", "stalls_over_5ms_per_minute", "required_window_ms",
        "predicted_overrun_fraction", "verdict"})
    EXPECT_TRUE(j["platform"].contains(key)) << key;
  EXPECT_DOUBLE_EQ(j["platform"]["rate_hz"].get<double>(), 100.0);
  EXPECT_EQ(j["holds"].get<bool>(), r.exit_code == 0);
  EXPECT_TRUE(j["fixes"].is_array());
  ASSERT_EQ(j["findings"].size(), 4u);
  // The first names each node kind's window, the watchdog following the answer window when unset.
  EXPECT_THAT(j["findings"][0].get<std::string>(),
              HasSubstr("the command watchdog of the actuator emulators and controller nodes"));
}

TEST(RtCheck, AConfigsDeploymentIsJudgedAndItsRateCannotBeOverridden) {
  const std::string config =
      std::string(RTHS_SOURCE_DIR) + "/configs/paper_frame_distributed.textproto";
  const auto bad = rths::test::run_command_line(kRths + " rt-check " + config + " --rate 100");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_THAT(bad.output, HasSubstr("--rate is for the default deployment"));
  const auto r = rths::test::run_command_line(kRths + " rt-check " + config + " --seconds 0.3");
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("wake-up lateness at 1000 Hz"));
  EXPECT_THAT(r.output, HasSubstr("a 15.0 s run"));
  const auto seconds = rths::test::run_command_line(kRths + " rt-check --seconds 0");
  EXPECT_EQ(seconds.exit_code, 2) << seconds.output;
}

}  // namespace
