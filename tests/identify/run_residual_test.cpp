// The system-level residual of a distributed run: the study re-run in process with the declared and
// with the identified actuators, each against the recorded response. Records from rths's own
// distributed runs (tests/identify/undeclared_run.h) with an actuator effect the config does not
// declare: the declared model must be off by >= 20 % NRMSE and the identified one reproduce the
// record to <= 2 %; a clean record re-runs exactly; the effect explaining the error is named.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "identify/run/run_record.h"
#include "tests/identify/undeclared_run.h"

namespace rths::identify {
namespace {

IdentifyOptions actuator_only() {
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  return options;
}

const RunResidual& residual_of(const RunIdentification& run) {
  EXPECT_TRUE(run.residual.has_value());
  static const RunResidual none;
  return run.residual ? *run.residual : none;
}

// The floor NRMSEs, on stdout for the report of the figures.
void print(const std::string& name, const RunResidual& r) {
  std::printf("%s: worst floor NRMSE declared %.4f -> identified %.4f over %zu steps\n",
              name.c_str(), r.declared, r.identified, r.steps);
}

TEST(RunResidual, ACleanRecordReRunsAsRecorded) {
  const RunIdentification run =
      identify_run_record(test::run_with_undeclared("residual_clean", ""), actuator_only());
  const RunResidual& r = residual_of(run);
  print("clean", r);
  ASSERT_EQ(r.floors.size(), 1u);
  EXPECT_EQ(r.steps, run.steps);
  EXPECT_LT(r.declared, 1e-9) << run_record_text(run);
  EXPECT_LT(r.identified, 0.02) << run_record_text(run);
  EXPECT_TRUE(r.effects.empty());
}

TEST(RunResidual, AnExtraFirstOrderLagIsReproducedByTheIdentifiedModel) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_first_order",
                                "receive_delay { first_order { time_constant: 0.008 } }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("first order 8 ms", r);
  EXPECT_GE(r.declared, 0.20) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  ASSERT_EQ(r.links.size(), 1u);
  EXPECT_NEAR(r.links[0].share, 1.0, 1e-12);
  EXPECT_NEAR(r.links[0].removed, r.declared - r.identified, 1e-12);
  ASSERT_FALSE(r.effects.empty()) << run_record_text(run);
  EXPECT_EQ(r.effects[0].effect, "first_order") << run_record_text(run);
  EXPECT_GT(r.effects[0].share, 0.9) << run_record_text(run);
}

TEST(RunResidual, AnEmulatorGainErrorIsReproducedAndNamedAsTheCause) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_gain",
                                "receive_delay { shift { delay: 0 } amplitude_gain: 1.25 }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("gain 1.25", r);
  EXPECT_GE(r.declared, 0.20) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  ASSERT_EQ(r.effects.size(), 1u) << run_record_text(run);
  EXPECT_EQ(r.effects[0].effect, "gain error");
  EXPECT_NEAR(r.effects[0].share, 1.0, 1e-12);
}

TEST(RunResidual, AnUndeclaredExtraDelayIsNamedAsADelayChangeAndReproduced) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_delay", "receive_delay { shift { delay: 0.006 } }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("extra delay 6 ms", r);
  EXPECT_NEAR(run.actuators.at(0).fitted_delay, 0.020, 2e-4) << run_record_text(run);
  EXPECT_GE(r.declared, 0.20) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  ASSERT_EQ(r.effects.size(), 1u) << run_record_text(run);
  EXPECT_EQ(r.effects[0].effect, "delay change");
  EXPECT_NEAR(r.effects[0].share, 1.0, 1e-12);
}

}  // namespace
}  // namespace rths::identify
