// Number flags with a range (cli/support.h finite_in) refuse NaN and infinities at parse time,
// exit 2 naming the flag, where CLI::Range let them through (every comparison with NaN is false);
// and a flag's range is what the later check accepts: `rths stability`'s damping error.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "tests/cli/cli_support.h"

namespace {

using namespace rths::cli_test;

const std::string kStability = "stability --period 0.5 --zeta 0.05 --exp-fraction 1 --dt 0.001";

TEST(FlagRanges, NonFiniteValuesAreRefusedAtParseTimeNamingTheFlag) {
  const std::vector<std::pair<std::string, std::string>> commands{
      {kStability + " --predictor-stiffness-error nan", "--predictor-stiffness-error"},
      {kStability + " --predictor-damping-error nan", "--predictor-damping-error"},
      {kStability + " --predictor-stiffness-error inf", "--predictor-stiffness-error"},
      {"identify measured.csv --holdout nan", "--holdout"},
      {"identify measured.csv --min-improvement nan", "--min-improvement"},
      {"identify measured.csv --search-tolerance inf", "--search-tolerance"},
      {"rt-check --seconds nan", "--seconds"},
      {"rt-check --rate -nan", "--rate"},
      {"rt-check --run-seconds inf", "--run-seconds"},
      {"launch " + (kSource / "configs/paper_frame.textproto").string() + " --platform-seconds nan",
       "--platform-seconds"},
  };
  for (const auto& [command, flag] : commands) {
    const Outcome o = run(command);
    EXPECT_EQ(o.exit_code, 2) << command << ": " << o.output;
    EXPECT_NE(o.output.find("is not a finite number"), std::string::npos)
        << command << ": " << o.output;
    EXPECT_NE(o.output.find(flag), std::string::npos) << command << ": " << o.output;
  }
}

// The node-side programs take the same check: the coordinator's --platform-seconds and the
// controller emulator's times refuse NaN and infinities at parse time too.
TEST(FlagRanges, TheCoordinatorAndTheControllerEmulatorRefuseNonFiniteTimes) {
  const std::string config = (kSource / "configs/paper_frame_controller.textproto").string();
  const std::string emulator =
      std::string(RTHS_CONTROLLER_EMULATOR) + " --config " + config + " --node-id 2 ";
  const std::vector<std::pair<std::string, std::string>> commands{
      {std::string(RTHS_COORDINATOR) + " --config " + config + " --platform-seconds nan",
       "--platform-seconds"},
      {emulator + "--answer-lag-ms nan", "--answer-lag-ms"},
      {emulator + "--answer-period-ms inf", "--answer-period-ms"},
      {emulator + "--idle-timeout nan", "--idle-timeout"},
  };
  for (const auto& [command, flag] : commands) {
    const Outcome o = rths::test::run_command_line(command);
    EXPECT_EQ(o.exit_code, 2) << command << ": " << o.output;
    EXPECT_NE(o.output.find("is not a finite number"), std::string::npos)
        << command << ": " << o.output;
    EXPECT_NE(o.output.find(flag), std::string::npos) << command << ": " << o.output;
  }
}

// The model's damping error is its damping ratio (the specimen's own is taken as 0), so >= 0:
// the range says so at parse time, and what it allows the analysis takes.
TEST(FlagRanges, StabilitysDampingErrorRangeAgreesWithItsLaterCheck) {
  Outcome o = run(kStability + " --predictor-damping-error -10");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("-10 is outside [0, 10]"), std::string::npos) << o.output;
  EXPECT_EQ(o.output.find("stability: the model's damping ratio must be >= 0"), std::string::npos)
      << o.output;
  for (const std::string value : {"0", "0.05", "10"}) {
    o = run(kStability + " --predictor-damping-error " + value + " --json");
    EXPECT_EQ(o.exit_code, 0) << value << ": " << o.output;
  }
}

}  // namespace
