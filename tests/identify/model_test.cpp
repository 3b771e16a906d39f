#include "identify/model/model.h"

#include <gtest/gtest.h>
#include <numbers>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/delay.h"
#include "core/rig_effects.h"
#include "identify/fit/evidence.h"

namespace rths::identify {
namespace {

constexpr double kDt = 0.001;

ChannelSignals sine_signals(Channel channel, double frequency = 2.0, std::size_t n = 3000) {
  MeasuredData d;
  d.dt = kDt;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * kDt;
    d.time.push_back(t);
    d.command.push_back(0.002 * std::sin(2 * std::numbers::pi * frequency * t));
    d.measured.push_back(0.002 * std::sin(2 * std::numbers::pi * frequency * t));
    d.force.push_back(0.0);
  }
  return make_signals(d, channel);
}

TEST(ModelTest, EffectNamesRoundTripAndApply) {
  for (Channel ch : {Channel::kMeasured, Channel::kForce}) {
    for (Effect e : effect_library(ch)) {
      EXPECT_EQ(parse_effect(effect_name(e)), e);
      EXPECT_TRUE(effect_applies(e, ch));
    }
  }
  EXPECT_FALSE(effect_applies(Effect::kCoulomb, Channel::kMeasured));
  EXPECT_FALSE(effect_applies(Effect::kFirstOrder, Channel::kForce));
  EXPECT_THROW(parse_effect("magic"), std::invalid_argument);
  EXPECT_EQ(effect_library(Channel::kMeasured).size() + effect_library(Channel::kForce).size(),
            19u);
}

TEST(ModelTest, FractionalDelayShiftsTheCommand) {
  const auto s = sine_signals(Channel::kMeasured);
  ChannelModel m = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(s));
  m.params = {1.0, 0.0125};
  const auto y = predict(m, s);
  for (std::size_t i = 100; i < s.size(); i += 97) {
    EXPECT_NEAR(y[i], 0.002 * std::sin(2 * std::numbers::pi * 2.0 * (s.time[i] - 0.0125)), 1e-6);
  }
}

TEST(ModelTest, FirstOrderMatchesTheCoreBlock) {
  const auto s = sine_signals(Channel::kMeasured, 5.0);
  const auto sc = signal_scales(s);
  ChannelModel m = with_effect(declared_model(Channel::kMeasured, {}, sc), Effect::kFirstOrder,
                               std::vector<double>{0.02});
  const auto y = predict(m, s);
  core::FirstOrderActuator block(0.02, kDt);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double expected = block.step({s.time[i], s.input[i], 0.0});
    if (i > 200) EXPECT_NEAR(y[i], expected, 1e-9) << i;  // both start at rest near zero input
  }
}

TEST(ModelTest, SecondOrderMatchesTheCoreTransferFunction) {
  const auto s = sine_signals(Channel::kMeasured, 8.0);
  const auto sc = signal_scales(s);
  const double wn = 2 * std::numbers::pi * 15.0, zeta = 0.5;
  ChannelModel m = with_effect(declared_model(Channel::kMeasured, {}, sc), Effect::kSecondOrder,
                               std::vector<double>{wn, zeta});
  const auto y = predict(m, s);
  core::TransferFunctionStage block({wn * wn}, {1.0, 2 * zeta * wn, wn * wn}, kDt);
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_NEAR(y[i], block.step({s.time[i], s.input[i], 0.0}), 1e-9) << i;
  }
}

TEST(ModelTest, BacklashHoldsWithinItsWidth) {
  const auto s = sine_signals(Channel::kMeasured);
  ChannelModel m = with_effect(declared_model(Channel::kMeasured, {}, signal_scales(s)),
                               Effect::kBacklash, std::vector<double>{0.001});
  const auto y = predict(m, s);
  double peak = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_LE(std::abs(y[i] - s.input[i]), 0.0005 + 1e-12);
    peak = std::max(peak, y[i]);
  }
  EXPECT_NEAR(peak, 0.002 - 0.0005, 1e-6);
}

// The rod's ends cut the sine's peaks (2 mm) at 1.5 mm and leave the rest; as the core's stage.
TEST(ModelTest, AStrokeLimitCutsThePeaksAtItsEnds) {
  const auto s = sine_signals(Channel::kMeasured);
  ChannelModel m = with_effect(declared_model(Channel::kMeasured, {}, signal_scales(s)),
                               Effect::kStrokeLimit, std::vector<double>{0.0015});
  const auto y = predict(m, s);
  core::MotionLimit rod = core::MotionLimit::stroke_limit(0.0015);
  double peak = 0.0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_DOUBLE_EQ(y[i], rod.step({s.time[i], s.input[i], 0.0})) << i;
    peak = std::max(peak, std::abs(y[i]));
  }
  EXPECT_DOUBLE_EQ(peak, 0.0015);
}

TEST(ModelTest, ForceModelSumsItsTerms) {
  auto s = sine_signals(Channel::kForce);
  const auto sc = signal_scales(s);
  ChannelModel m = declared_model(Channel::kForce, {Effect::kStiffness}, sc);
  m = with_effect(m, Effect::kDamping, std::vector<double>{100.0});
  m = with_effect(m, Effect::kOffsetDrift, std::vector<double>{5.0, 0.0});
  m.params[0] = 1e5;
  const auto f = predict(m, s);
  // The specimen runs on the low-passed displacement when there is one.
  const auto& d = s.model_input.empty() ? s.input : s.model_input;
  for (std::size_t i = 10; i < s.size(); i += 101) {
    EXPECT_NEAR(f[i], 1e5 * d[i] + 100.0 * s.velocity[i] + 5.0, 1e-9);
  }
  EXPECT_EQ(m.param(Effect::kDamping, "damping", sc).value(), 100.0);
  EXPECT_FALSE(m.param(Effect::kCoulomb, "friction_force", sc).has_value());
}

TEST(ModelTest, BoucWenIsBoundedAndHysteretic) {
  auto s = sine_signals(Channel::kForce);
  ChannelModel m = declared_model(Channel::kForce, {}, signal_scales(s));
  m = with_effect(m, Effect::kBoucWen, std::vector<double>{10.0, 0.0002});
  const auto f = predict(m, s);
  for (double v : f) EXPECT_LE(std::abs(v), 10.0 + 1e-12);
  // Hysteresis: at zero displacement the force is non-zero and its sign follows the velocity.
  for (std::size_t i = 600; i + 1 < s.size(); ++i) {
    if (s.input[i] <= 0.0 && s.input[i + 1] > 0.0) EXPECT_GT(f[i], 5.0);
    if (s.input[i] >= 0.0 && s.input[i + 1] < 0.0) EXPECT_LT(f[i], -5.0);
  }
}

TEST(ModelTest, PhysicalParametersAreBoundedAtZero) {
  const auto s = sine_signals(Channel::kForce);
  const auto sc = signal_scales(s);
  for (Effect e : {Effect::kStiffness, Effect::kDamping, Effect::kInertia}) {
    const auto spec = effect_params(e, Channel::kForce, sc).front();
    EXPECT_EQ(spec.lower, 0.0) << effect_name(e);
    EXPECT_FALSE(spec.below_means.empty()) << effect_name(e);
  }
  const auto delay = effect_params(Effect::kDelay, Channel::kMeasured, sc).front();
  EXPECT_EQ(delay.lower, 0.0);
  EXPECT_LE(delay.upper, 0.5 * sc.duration);
  const auto wn = effect_params(Effect::kSecondOrder, Channel::kMeasured, sc).front();
  EXPECT_LE(wn.upper, std::numbers::pi / kDt + 1e-9);  // finite bandwidth: below Nyquist
}

TEST(ModelTest, DriftProfileIsZeroMeanOverTheRecord) {
  const std::vector<double> c{0.3, -0.2, 0.1, 0.05, 0.0, 0.02, 0.0, 0.0};
  double sum = 0.0;
  const int n = 10000;
  for (int i = 0; i < n; ++i) sum += drift_profile(c, (i + 0.5) / n - 0.5);
  EXPECT_NEAR(sum / n, 0.0, 1e-6);
  EXPECT_NEAR(drift_profile(c, -0.5), 0.3 - 0.2 + 0.1 + 0.05 + 0.0 + 0.02, 1e-12);  // cos(0) = 1
}

TEST(ModelTest, ElastoPlasticForceStaysWithinTheYieldForce) {
  auto s = sine_signals(Channel::kForce);
  ChannelModel m = declared_model(Channel::kForce, {}, signal_scales(s));
  m = with_effect(m, Effect::kElastoPlastic, std::vector<double>{1e6, 50.0});
  const auto f = predict(m, s);
  double peak = 0.0;
  for (double v : f) peak = std::max(peak, std::abs(v));
  EXPECT_NEAR(peak, 50.0, 1e-9);  // 1e6 N/m over 2 mm would be 2 kN elastic
  // Elastic at first (25 N < 50 N), on the displacement the specimen runs on.
  const auto& d = s.model_input.empty() ? s.input : s.model_input;
  EXPECT_NEAR(f[1], 1e6 * (d[1] - d[0]), 1e-9);
}

TEST(ModelTest, WithoutEffectRemovesItsParameters) {
  auto s = sine_signals(Channel::kForce);
  const auto sc = signal_scales(s);
  ChannelModel m = declared_model(Channel::kForce, {Effect::kStiffness}, sc);
  m = with_effect(m, Effect::kBoucWen, std::vector<double>{10.0, 0.0002});
  m = with_effect(m, Effect::kDamping, std::vector<double>{100.0});
  const ChannelModel less = without_effect(m, Effect::kBoucWen, sc);
  EXPECT_EQ(less.effects, (std::vector<Effect>{Effect::kStiffness, Effect::kDamping}));
  EXPECT_EQ(less.params, (std::vector<double>{0.0, 100.0}));
  EXPECT_EQ(m.effect_of(2, sc), Effect::kBoucWen);
  EXPECT_THROW(without_effect(less, Effect::kBoucWen, sc), std::invalid_argument);
}

// The zero-phase low-pass passes the band unchanged and in phase, and stops what lies far above.
TEST(ModelTest, ZeroPhaseLowpassKeepsTheBandAndItsPhase) {
  const double cutoff = 40.0;
  std::vector<double> slow, fast;
  for (std::size_t i = 0; i < 4000; ++i) {
    const double t = static_cast<double>(i) * kDt;
    slow.push_back(std::sin(2 * std::numbers::pi * 8.0 * t));
    fast.push_back(std::sin(2 * std::numbers::pi * 160.0 * t));
  }
  const auto slow_out = zero_phase_lowpass(slow, kDt, cutoff);
  const auto fast_out = zero_phase_lowpass(fast, kDt, cutoff);
  double fast_peak = 0.0;
  for (std::size_t i = 500; i < 3500; ++i) {  // away from the ends' start-up
    // |H| = 1 / (1 + (f / fc)^8): 0.99997 at 8 Hz; no phase, so sample by sample.
    EXPECT_NEAR(slow_out[i], slow[i], 2e-4) << i;
    fast_peak = std::max(fast_peak, std::abs(fast_out[i]));
  }
  EXPECT_LT(fast_peak, 2.0 / (1.0 + std::pow(160.0 / cutoff, 8)));
  EXPECT_THROW(zero_phase_lowpass(slow, kDt, 500.0), std::invalid_argument);
  EXPECT_THROW(zero_phase_lowpass(slow, kDt, 0.0), std::invalid_argument);
}

// The force channel's model input is the displacement low-passed at max(2.5x its signal band, its
// noise edge); the measured displacement itself is kept as it is; the actuator's clean command is
// not filtered. A 2 Hz sine with 1 um of sensor noise: the Hann window's leakage of the strong sine
// reaches the noise near 50 Hz, which sets the cut-off; the noise above it is gone.
TEST(ModelTest, OnlyTheSpecimenInputIsLowPassed) {
  MeasuredData d;
  d.dt = kDt;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 1e-6);
  for (std::size_t i = 0; i < 4000; ++i) {
    const double t = static_cast<double>(i) * kDt;
    d.time.push_back(t);
    d.command.push_back(0.002 * std::sin(2 * std::numbers::pi * 2.0 * t));
    d.measured.push_back(d.command.back() + noise(rng));
    d.force.push_back(0.0);
  }
  const auto force = make_signals(d, Channel::kForce);
  const double band = signal_band(force.input, kDt), edge = noise_edge(force.input, kDt);
  EXPECT_NEAR(band, 2.0, 0.3);
  EXPECT_GT(edge, band);
  EXPECT_LT(edge, 100.0);
  EXPECT_NEAR(force.input_cutoff, std::max(kSpecimenInputCutoffFactor * band, edge), 1e-12);
  ASSERT_EQ(force.model_input.size(), force.size());
  double left = 0.0;
  for (std::size_t i = 500; i < 3500; ++i) {
    EXPECT_EQ(force.input[i], d.measured[i]);
    left += std::pow(force.model_input[i] - d.command[i], 2) / 3000.0;
  }
  // White noise of 1 um rms over 0-500 Hz keeps sqrt(f_c / 500 Hz) of its rms below f_c.
  EXPECT_LT(std::sqrt(left), 1e-6 * std::sqrt(1.2 * force.input_cutoff / 500.0));
  const auto measured = make_signals(d, Channel::kMeasured);
  EXPECT_TRUE(measured.model_input.empty());
  EXPECT_EQ(measured.input_cutoff, 0.0);
}

TEST(ModelTest, NormalisedError) {
  const std::vector<double> target{1, -1, 1, -1}, perfect = target, zero(4, 0.0);
  const std::vector<std::size_t> all{0, 1, 2, 3};
  EXPECT_DOUBLE_EQ(normalised_error(target, perfect, all), 0.0);
  EXPECT_DOUBLE_EQ(normalised_error(target, zero, all), 1.0);
  EXPECT_THROW(normalised_error(target, zero, std::vector<std::size_t>{}), std::invalid_argument);
}

TEST(ModelTest, AddingAnEffectTwiceIsAnError) {
  auto s = sine_signals(Channel::kMeasured);
  ChannelModel m = declared_model(Channel::kMeasured, {Effect::kDelay}, signal_scales(s));
  EXPECT_THROW(with_effect(m, Effect::kDelay, std::vector<double>{0.0}), std::invalid_argument);
  EXPECT_THROW(effect_params(Effect::kInertia, Channel::kMeasured, signal_scales(s)),
               std::invalid_argument);
}

}  // namespace
}  // namespace rths::identify
