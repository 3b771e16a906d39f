#include "identify/lab/bode.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <filesystem>
#include <numbers>

#include "identify/fit/identify.h"
#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

constexpr double kDelay = 0.012, kTimeConstant = 0.015;

// The closed form of a first-order lag behind a pure delay: e^{-i w tau} / (1 + i w T).
std::complex<double> first_order_plus_delay(double f) {
  const double w = 2.0 * std::numbers::pi * f;
  return std::polar(1.0, -w * kDelay) / std::complex<double>(1.0, w * kTimeConstant);
}

std::size_t nearest(const std::vector<double>& x, double value) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < x.size(); ++k) {
    if (std::abs(x[k] - value) < std::abs(x[best] - value)) best = k;
  }
  return best;
}

double degrees(std::complex<double> h) { return std::arg(h) * 180.0 / std::numbers::pi; }

// The model's response is its recursion's: (1 - a) / (1 - a e^{-i w dt}) tends to the continuous
// lag as dt -> 0, and the Tustin biquad has unit DC gain and -90 degrees at its natural frequency
// (pre-warped: exactly at v = wn).
TEST(BodeTest, ModelResponseIsTheRecursionsAndTendsToTheClosedForm) {
  SignalScales scales;
  ChannelModel model = declared_model(Channel::kMeasured, {Effect::kDelay}, scales);
  model = with_effect(model, Effect::kFirstOrder, std::vector<double>{kTimeConstant});
  model.params[1] = kDelay;
  for (double f : {0.5, 3.0, 12.0}) {
    const std::complex<double> fine = actuator_response(model, f, 1e-6);
    EXPECT_NEAR(std::abs(fine - first_order_plus_delay(f)), 0.0, 1e-4) << f;
    const double dt = 0.002, a = std::exp(-dt / kTimeConstant), w = 2.0 * std::numbers::pi * f;
    const std::complex<double> recursion =
        std::polar(1.0, -w * kDelay) * (1.0 - a) / (1.0 - a * std::polar(1.0, -w * dt));
    EXPECT_NEAR(std::abs(actuator_response(model, f, 0.002) - recursion), 0.0, 1e-12) << f;
  }
  ChannelModel second = declared_model(Channel::kMeasured, {}, scales);
  const double dt = 0.001, wn = 2.0 * std::numbers::pi * 20.0;
  second = with_effect(second, Effect::kSecondOrder, std::vector<double>{wn, 0.3});
  EXPECT_NEAR(std::abs(actuator_response(second, 1e-6, dt)), 1.0, 1e-9);
  const double f_warped = std::atan(wn * dt / 2.0) / (std::numbers::pi * dt);
  EXPECT_NEAR(degrees(actuator_response(second, f_warped, dt)), -90.0, 1e-6);
  EXPECT_THROW(actuator_response(declared_model(Channel::kForce, {}, scales), 1.0, dt),
               std::invalid_argument);
}

// Generated data with a known actuator (12 ms delay, 15 ms first-order lag, chirp 0.3-12 Hz):
// the measured H1 and the identified model's response both match the closed form at a few
// frequencies; the declared model (delay and gain only) has no attenuation with frequency.
// Tolerances: 1.5 % and 1.5 degrees, of which up to w dt / 2 (1.1 degrees at 6 Hz) is the
// recursion's half-sample lead over the continuous lag.
TEST(BodeTest, MeasuredAndIdentifiedResponseMatchAKnownActuator) {
  GeneratorSpec spec;
  spec.dt = 0.001;
  spec.duration = 30.0;
  spec.delay = kDelay;
  spec.first_order_time_constant = kTimeConstant;
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  const Identification id = identify(generate_measured(spec), options);
  const ChannelIdentification& c = id.channels.at(0);
  ASSERT_TRUE(c.final_fit.model.has(Effect::kFirstOrder));
  const BodeData bode = actuator_bode(
      id.signals.at(0), {{"identified", &c.final_fit.model}, {"declared", &c.declared_fit.model}});
  ASSERT_EQ(bode.models.size(), 2u);
  EXPECT_LT(bode.band_low, 0.5);
  EXPECT_GT(bode.band_high, 11.0);
  EXPECT_LT(bode.band_high, 16.0);  // the chirp stops at 12 Hz: little coherence beyond
  EXPECT_GE(bode.segments, 8u);
  for (double c2 : bode.coherence) EXPECT_GE(c2, 0.9);
  for (double f : {1.0, 3.0, 6.0}) {
    const std::size_t k = nearest(bode.frequency, f);
    ASSERT_NEAR(bode.frequency[k], f, 0.2);
    const std::complex<double> truth = first_order_plus_delay(bode.frequency[k]);
    EXPECT_NEAR(bode.amplitude[k], std::abs(truth), 0.015 * std::abs(truth)) << f;
    EXPECT_NEAR(bode.phase_deg[k], degrees(truth), 1.5) << f;
    EXPECT_NEAR(bode.models[0].amplitude[k], std::abs(truth), 0.015 * std::abs(truth)) << f;
    EXPECT_NEAR(bode.models[0].phase_deg[k], degrees(truth), 1.5) << f;
  }
  // The declared model's amplitude is its gain at every frequency, the measured one falls.
  const std::size_t k1 = nearest(bode.frequency, 1.0), k6 = nearest(bode.frequency, 6.0);
  EXPECT_NEAR(bode.models[1].amplitude[k1], bode.models[1].amplitude[k6], 1e-9);
  EXPECT_GT(bode.amplitude[k1], 1.05 * bode.amplitude[k6]);

  const auto dir = std::filesystem::temp_directory_path() / "rths_identify_bode_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  write_bode_plot(bode, dir / "measured_bode.png");
  EXPECT_GT(std::filesystem::file_size(dir / "measured_bode.png"), 1000u);
  EXPECT_GT(std::filesystem::file_size(dir / "measured_bode.svg"), 1000u);
  std::filesystem::remove_all(dir);
}

TEST(BodeTest, RefusesTheForceChannelAndShortRecords) {
  GeneratorSpec spec;
  const MeasuredData data = generate_measured(spec);
  EXPECT_THROW(actuator_bode(make_signals(data, Channel::kForce), {}), std::invalid_argument);
  EXPECT_THROW(actuator_bode(make_signals(slice(data, 0, 300), Channel::kMeasured), {}),
               std::invalid_argument);
}

}  // namespace
}  // namespace rths::identify
