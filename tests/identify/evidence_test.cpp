#include "identify/fit/evidence.h"

#include <gtest/gtest.h>
#include <numbers>

#include <cmath>
#include <random>

#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

TEST(EvidenceTest, SpectrumFindsASineAndItsAmplitude) {
  const double dt = 0.002;
  std::vector<double> x(5000);
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = 3.0 * std::sin(2 * std::numbers::pi * 7.0 * i * dt) + 1.0;
  const Spectrum s = amplitude_spectrum(x, dt);
  std::size_t peak = 1;
  for (std::size_t k = 1; k < s.amplitude.size(); ++k) {
    if (s.amplitude[k] > s.amplitude[peak]) peak = k;
  }
  EXPECT_NEAR(s.frequency[peak], 7.0, 0.1);
  EXPECT_NEAR(s.amplitude[peak], 3.0, 0.3);
  EXPECT_LT(s.amplitude[0], 1e-6);  // mean removed
}

TEST(EvidenceTest, CrossCorrelationFindsASubSampleLag) {
  const double dt = 0.001;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  std::vector<double> a(4000), b(4000);
  double state = 0.0;
  for (auto& v : a) v = state = 0.95 * state + normal(rng);  // smooth random signal
  for (std::size_t i = 0; i < b.size(); ++i) {
    const double pos = static_cast<double>(i) - 12.4;
    const auto j = static_cast<std::size_t>(std::max(0.0, std::floor(pos)));
    const double f = pos - std::floor(pos);
    b[i] = pos < 0 ? a[0] : a[j] + f * (a[std::min(j + 1, a.size() - 1)] - a[j]);
  }
  const CrossCorrelation c = cross_correlation(a, b, dt, 0.05);
  EXPECT_NEAR(c.lag, 0.0124, 0.0005);
  EXPECT_GT(c.peak, 0.95);
  const CrossCorrelation reverse = cross_correlation(b, a, dt, 0.05);
  EXPECT_NEAR(reverse.lag, -0.0124, 0.0005);
}

TEST(EvidenceTest, ResidualProportionalToVelocityShowsInTheEvidence) {
  ChannelSignals s;
  s.dt = 0.001;
  for (std::size_t i = 0; i < 4000; ++i) {
    const double t = i * s.dt;
    s.time.push_back(t);
    s.input.push_back(std::sin(2 * std::numbers::pi * 2 * t));
    s.velocity.push_back(2 * std::numbers::pi * 2 * std::cos(2 * std::numbers::pi * 2 * t));
    s.acceleration.push_back(-std::pow(2 * std::numbers::pi * 2, 2) *
                             std::sin(2 * std::numbers::pi * 2 * t));
    s.target.push_back(5.0 * s.input.back() + 0.3 * s.velocity.back());
  }
  std::vector<double> prediction(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) prediction[i] = 5.0 * s.input[i];
  const Evidence e = residual_evidence(s, prediction);
  EXPECT_GT(e.corr_velocity, 0.99);
  EXPECT_LT(std::abs(e.corr_input), 0.05);
  EXPECT_NEAR(e.dominant_frequency, 2.0, 0.3);
  EXPECT_THROW(residual_evidence(s, std::vector<double>(3)), std::invalid_argument);
}

TEST(EvidenceTest, CorrelationOfConstantIsZero) {
  const std::vector<double> a{1, 2, 3}, c{4, 4, 4};
  EXPECT_DOUBLE_EQ(correlation(a, c), 0.0);
  EXPECT_NEAR(correlation(a, a), 1.0, 1e-12);
}

TEST(EvidenceTest, NoiseFloorFindsTheGeneratorsNoise) {
  GeneratorSpec spec;
  spec.force_noise = 200.0;  // N rms, against a force of about 280 N rms
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kForce);
  double mean = 0.0, var = 0.0;
  for (double f : s.target) mean += f / static_cast<double>(s.size());
  for (double f : s.target) var += (f - mean) * (f - mean) / static_cast<double>(s.size());
  const double truth = spec.force_noise / std::sqrt(var);
  EXPECT_NEAR(noise_floor(s.input, s.target, s.dt), truth, 0.1 * truth);
  spec.force_noise = 0.0;
  const ChannelSignals clean = make_signals(generate_measured(spec), Channel::kForce);
  EXPECT_LT(noise_floor(clean.input, clean.target, clean.dt), 0.01);
}

// H1 by Welch of a pure 3-sample delay of white noise: unit magnitude, phase -w 3 dt, coherence 1;
// with independent noise on the output the coherence falls to S_signal / (S_signal + S_noise).
TEST(EvidenceTest, TransferEstimateOfAKnownDelay) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  const double dt = 0.001;
  std::vector<double> x(40000), y(40000), noisy(40000);
  for (double& v : x) v = normal(rng);
  for (std::size_t i = 0; i < x.size(); ++i) {
    y[i] = i >= 3 ? x[i - 3] : 0.0;
    noisy[i] = y[i] + normal(rng);
  }
  const TransferEstimate h = transfer_estimate(x, y, dt, 1024);
  EXPECT_EQ(h.segments, 2 * 40000 / 1024 - 1);
  ASSERT_EQ(h.frequency.size(), 512u);
  EXPECT_NEAR(h.frequency.front(), 1.0 / (1024 * dt), 1e-9);
  for (std::size_t k = 0; k < h.frequency.size(); k += 50) {
    EXPECT_NEAR(h.magnitude[k], 1.0, 0.01) << h.frequency[k];
    EXPECT_NEAR(h.phase[k], -2.0 * std::numbers::pi * h.frequency[k] * 3.0 * dt, 0.01)
        << h.frequency[k];
    EXPECT_GT(h.coherence[k], 0.99) << h.frequency[k];
  }
  const TransferEstimate n = transfer_estimate(x, noisy, dt, 1024);
  double mean_coherence = 0.0;
  for (double c : n.coherence) mean_coherence += c / static_cast<double>(n.coherence.size());
  EXPECT_NEAR(mean_coherence, 0.5, 0.05);
  EXPECT_THROW(transfer_estimate(x, std::vector<double>(10, 0.0), dt, 8), std::invalid_argument);
  EXPECT_THROW(
      transfer_estimate(std::vector<double>(100, 0.0), std::vector<double>(100, 0.0), dt, 256),
      std::invalid_argument);
}

// A chirp to 12 Hz with 2 um of sensor noise: its band ends near 12 Hz and its spectrum sinks to
// the noise just above; a record too short to estimate from gives 0.
TEST(EvidenceTest, NoiseEdgeIsWhereTheSpectrumSinksToTheNoise) {
  GeneratorSpec spec;
  const MeasuredData data = generate_measured(spec);
  const double band = signal_band(data.measured, data.dt),
               edge = noise_edge(data.measured, data.dt);
  EXPECT_GT(band, 8.0);
  EXPECT_LT(band, 12.5);
  EXPECT_GT(edge, band);
  EXPECT_LT(edge, 25.0);
  EXPECT_EQ(noise_edge(std::vector<double>(100, 1.0), data.dt), 0.0);
}

}  // namespace
}  // namespace rths::identify
