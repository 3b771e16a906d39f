#include "identify/fit/identify.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <iostream>

#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

const std::filesystem::path kRealFile =
    std::filesystem::path(RTHS_DATA_DIR) / "measured/mts_mrdamper_chirp_0A.txt";

// The MTS actuator lags its command by about 17 ms; a pure delay (+ gain) still leaves ~38 % on
// held-out data. The search finds what is missing; the errors are measured at the full rate.
TEST(IdentifyTest, RealActuatorHeldOutErrorFallsBelowFivePercent) {
  const MeasuredData data = read_measured(kRealFile);
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  const Identification id = identify(data, options);
  ASSERT_EQ(id.channels.size(), 1u);
  const ChannelIdentification& c = id.channels[0];
  EXPECT_GT(id.search_decimation, 1u);
  EXPECT_EQ(id.split.size, data.size());
  EXPECT_GT(c.declared_fit.heldout_error, 0.30);
  EXPECT_LT(c.declared_fit.heldout_error, 0.45);
  const auto delay =
      c.declared_fit.model.param(Effect::kDelay, "delay", signal_scales(id.signals[0]));
  EXPECT_NEAR(delay.value(), 0.017, 0.003);
  ASSERT_FALSE(c.steps.empty());
  EXPECT_LT(c.final_fit.heldout_error, 0.05);
  EXPECT_DOUBLE_EQ(c.steps.front().before.heldout_error, c.declared_fit.heldout_error);
  EXPECT_DOUBLE_EQ(c.steps.back().after.heldout_error, c.final_fit.heldout_error);
  EXPECT_EQ(c.final_fit.prediction.size(), data.size());  // full rate
}

// The MR damper's force: a spring is the wrong kind (the data want a negative stiffness); the
// tool proposes a damper with hysteresis, fits no negative stiffness or damping, and ends near
// the noise floor it estimates from the record. The specimen model runs on the displacement
// low-passed at 2.5x its signal band (model.h make_signals): before, the raw displacement's
// sensor noise switched the hysteresis and the friction at every reversal of the noise.
void expect_hysteretic_damper(const Identification& id) {
  const ChannelIdentification& c = id.channels.at(0);
  ASSERT_TRUE(c.kind.has_value());
  ASSERT_TRUE(c.kind->proposed.has_value());
  EXPECT_TRUE(is_hysteretic_damper(*c.kind->proposed));
  const auto sc = signal_scales(id.signals[0]);
  EXPECT_GE(c.final_fit.model.param(Effect::kStiffness, "stiffness", sc).value_or(0.0), 0.0);
  EXPECT_GT(c.final_fit.model.param(Effect::kDamping, "damping", sc).value_or(0.0), 0.0);
  EXPECT_GT(c.final_fit.model.param(Effect::kBoucWen, "hysteretic_force", sc).value_or(0.0), 0.0);
  for (std::size_t i = 0; i < c.final_fit.model.params.size(); ++i) {
    const auto spec = c.final_fit.model.specs(sc)[i];
    if (!spec.below_means.empty()) EXPECT_GE(c.final_fit.model.params[i], 0.0) << spec.name;
  }
  EXPECT_GT(id.signals[0].input_cutoff, 0.0);
  std::cout << c.final_fit.model.describe(sc) << "\nheld-out " << c.final_fit.heldout_error
            << " noise floor " << c.noise_floor << " ratio "
            << c.final_fit.heldout_error / c.noise_floor << " (input low-passed at "
            << id.signals[0].input_cutoff << " Hz)\n";
}

// Whole record. Measured 27.76 % against a floor of 17.96 % (1.55x; 29.4 %, 1.64x, before the
// low-pass).
TEST(IdentifyTest, RealDamperForceIsAHystereticDamperNearTheNoiseFloor) {
  const MeasuredData data = read_measured(kRealFile);
  IdentifyOptions options;
  options.channels = {Channel::kForce};
  const Identification id = identify(data, options);
  expect_hysteretic_damper(id);
  const ChannelIdentification& c = id.channels.at(0);
  EXPECT_GT(c.noise_floor, 0.10);
  EXPECT_LT(c.noise_floor, 0.30);
  EXPECT_LT(c.final_fit.heldout_error, 1.6 * c.noise_floor);
}

// The same force on the record's active part (data.h active_range, `--trim-idle`), issue 14's
// target: a held-out error within 1.5x the noise floor. Measured 27.5 % against 18.83 % (1.46x;
// 28.85 %, 1.53x, before the low-pass).
TEST(IdentifyTest, RealDamperForceOnTheActivePartIsWithinOneAndAHalfNoiseFloors) {
  const MeasuredData data = read_measured(kRealFile);
  const ActiveRange active = active_range(data);
  IdentifyOptions options;
  options.channels = {Channel::kForce};
  const Identification id = identify(slice(data, active.begin, active.end), options);
  expect_hysteretic_damper(id);
  const ChannelIdentification& c = id.channels.at(0);
  EXPECT_LE(c.final_fit.heldout_error, 1.5 * c.noise_floor);
}

TEST(IdentifyTest, BothChannelsOfAGeneratedSetInOrder) {
  GeneratorSpec spec;
  spec.first_order_time_constant = 0.01;
  spec.cubic_stiffness = 1.5e10;
  const Identification id = identify(generate_measured(spec));
  ASSERT_EQ(id.channels.size(), 2u);
  const auto steps = id.steps();
  ASSERT_GE(steps.size(), 2u);
  EXPECT_EQ(steps.front()->channel, Channel::kMeasured);
  EXPECT_EQ(steps.front()->effect, Effect::kFirstOrder);
  EXPECT_EQ(steps.back()->channel, Channel::kForce);
  EXPECT_NE(id.find(Channel::kForce), nullptr);
  EXPECT_TRUE(id.find(Channel::kForce)->final_fit.model.has(Effect::kCubicStiffness));
}

// Labs record at 200 Hz to 4096 Hz: the step comes from the time column (through a CSV round
// trip), and the lag's time constant is found in seconds whatever the rate.
class SamplingRateTest : public ::testing::TestWithParam<double> {};

TEST_P(SamplingRateTest, FirstOrderLagFoundInSeconds) {
  GeneratorSpec spec;
  spec.dt = 1.0 / GetParam();
  spec.duration = 12.0;
  spec.first_order_time_constant = 0.02;
  const auto path = std::filesystem::temp_directory_path() /
                    ("rths_identify_rate_" + std::to_string(static_cast<int>(GetParam())) + ".csv");
  write_csv(generate_measured(spec), path);
  const MeasuredData data = read_measured(path);
  std::filesystem::remove(path);
  EXPECT_NEAR(data.dt, spec.dt, 1e-4 * spec.dt);
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  const Identification id = identify(data, options);
  const auto& c = id.channels.at(0);
  ASSERT_FALSE(c.steps.empty());
  EXPECT_EQ(c.steps.front().effect, Effect::kFirstOrder);
  EXPECT_NEAR(
      c.final_fit.model.param(Effect::kFirstOrder, "time_constant", signal_scales(id.signals[0]))
          .value(),
      0.02, 0.002);
}

INSTANTIATE_TEST_SUITE_P(Rates, SamplingRateTest, ::testing::Values(200.0, 4096.0));

TEST(IdentifyTest, DecimatedSearchAgreesWithTheFullRate) {
  GeneratorSpec spec;
  spec.offset = 2e-4;
  spec.dt = 0.001;
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  options.search_decimation = 4;
  const Identification id = identify(generate_measured(spec), options);
  ASSERT_EQ(id.channels[0].steps.size(), 1u);
  EXPECT_EQ(id.channels[0].steps[0].effect, Effect::kOffsetDrift);
  EXPECT_EQ(id.search_decimation, 4u);
  EXPECT_LT(id.channels[0].final_fit.heldout_error, 0.01);
}

}  // namespace
}  // namespace rths::identify
