// The description of a residual (identify/residual/description.h) on residuals made to hold one
// signature each beside a model's output like a storey's drift: noise alone is not described, a
// sinusoid is periodic at its frequency (also at one a broadband motion holds, where a lag's
// residual is not), a residual of the input's sign or amplitude or of its direction is the map's,
// one of the rate's sign or amplitude the rate map's, and a gain that moves over the record is
// time-varying with its change and its shape (a line, a step with its time, an exponential
// approach), and a lead on the model that moves over the record time-varying of the rate.
#include "identify/residual/description.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace rths::identify {
namespace {

constexpr double kDt = 0.001;
constexpr std::size_t kSamples = 15000;

struct Synthetic {
  std::vector<double> time, prediction, residual;
};

// A model's output like a storey's drift under a ground motion (mm, several frequencies and an
// envelope), and Gaussian noise of `noise` as the residual.
Synthetic synthetic(double noise, std::uint64_t seed = 3) {
  Synthetic out;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t j = 0; j < kSamples; ++j) {
    const double t = static_cast<double>(j) * kDt, w = 2.0 * std::numbers::pi;
    const double envelope = 0.5 + 0.5 * std::sin(w * 0.05 * t);
    out.time.push_back(t);
    out.prediction.push_back(envelope *
                             (8.0 * std::sin(w * 1.9 * t) + 3.0 * std::sin(w * 0.7 * t + 1.0) +
                              1.5 * std::sin(w * 3.3 * t + 2.0)));
    out.residual.push_back(noise * normal(rng));
  }
  return out;
}

ResidualDescription described(const Synthetic& s) {
  return describe_residual(s.time, s.residual, s.prediction, kDt);
}

TEST(DescribeResidual, NoiseAloneIsNotDescribed) {
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const ResidualDescription d = described(synthetic(0.05, seed));
    EXPECT_FALSE(d.any()) << "seed " << seed << ": " << d.kinds().size() << " kinds";
  }
}

TEST(DescribeResidual, ASinusoidIsPeriodicWithItsFrequencyAndAmplitude) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += 0.3 * std::sin(2.0 * std::numbers::pi * 7.0 * s.time[j] + 0.4);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.periodic.has_value());
  EXPECT_NEAR(d.periodic->frequency, 7.0, 0.01);
  EXPECT_NEAR(d.periodic->amplitude, 0.3, 0.015);
  EXPECT_FALSE(d.amplitude || d.direction || d.time_varying);
  EXPECT_GT(d.explained, 0.9);
}

// A load cell's slow thermal cycle, 1.95 cycles in the 15 s record (0.13 Hz, below
// kMinPeriodicFrequency), is periodic at its frequency: the slow band starts at
// kMinPeriodicCycles in the record.
TEST(DescribeResidual, ASlowCycleUnderTwoInTheRecordIsPeriodic) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += 0.3 * std::sin(2.0 * std::numbers::pi * 0.13 * s.time[j] + 0.4);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.periodic.has_value());
  EXPECT_NEAR(d.periodic->frequency, 0.13, 0.13 * 0.05);
  EXPECT_NEAR(d.periodic->amplitude, 0.3, 0.03);
}

// Slow drifts are no period, though their spectra pile up in the slow band: an offset that
// approaches its end value (time constant 4 s), one that grows as the square of time and one that
// rises and settles back once (a single hump, under one cycle).
TEST(DescribeResidual, ASlowDriftIsNotPeriodic) {
  const std::vector<double (*)(double)> drifts{
      [](double t) { return 0.4 * (1.0 - std::exp(-t / 4.0)); },
      [](double t) { return 0.4 * (t / 15.0) * (t / 15.0); },
      [](double t) { return 0.4 * std::sin(std::numbers::pi * t / 15.0); }};
  for (std::size_t i = 0; i < drifts.size(); ++i) {
    Synthetic s = synthetic(0.05);
    for (std::size_t j = 0; j < kSamples; ++j) s.residual[j] += drifts[i](s.time[j]);
    EXPECT_FALSE(described(s).periodic.has_value())
        << "drift " << i << " at " << described(s).periodic->frequency << " Hz";
  }
}

// Stiffer on one side than on the other: a residual even in the input.
TEST(DescribeResidual, AResidualOfTheInputsSignIsDirectionWithItsAsymmetry) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j) s.residual[j] += 0.1 * std::abs(s.prediction[j]);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.direction.has_value());
  EXPECT_NEAR(d.direction->asymmetry_pct, 20.0, 2.0);  // +10 % on one side, -10 % on the other
  EXPECT_FALSE(d.periodic || d.amplitude);
}

TEST(DescribeResidual, AReadingThatFallsShortAtLargeInputsIsAmplitude) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] -= 0.002 * s.prediction[j] * s.prediction[j] * s.prediction[j];
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.amplitude.has_value());
  EXPECT_LT(d.amplitude->ratio_change_pct, -5.0);
  EXPECT_FALSE(d.periodic || d.direction);
}

TEST(DescribeResidual, LoadingAndUnloadingApartIsDirectionWithItsWidth) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 1; j < kSamples; ++j)
    s.residual[j] += s.prediction[j] >= s.prediction[j - 1] ? 0.2 : -0.2;
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.direction.has_value());
  EXPECT_NEAR(d.direction->hysteresis_width, 0.4, 0.05);
}

TEST(DescribeResidual, AGainThatFallsOverTheRecordIsTimeVaryingWithItsChange) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += -0.2 * (s.time[j] / s.time.back() - 0.5) * s.prediction[j];
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.time_varying.has_value());
  EXPECT_NEAR(d.time_varying->change_pct, -20.0, 2.0);
  EXPECT_EQ(d.time_varying->shape.shape, DriftShape::kLinear);  // +10 % to -10 %, steadily
  EXPECT_NEAR(d.time_varying->shape.start, 0.1, 0.02);
  EXPECT_NEAR(d.time_varying->shape.end, -0.1, 0.02);
  EXPECT_FALSE(d.periodic || d.amplitude || d.direction);
}

// A gain that drops by 30 % at 9 s of the 15 s record: time-varying, shaped as a step there,
// from 0 to -30 % measured / model.
TEST(DescribeResidual, AGainThatDropsAtAMomentIsAStepWithItsTime) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    if (s.time[j] >= 9.0) s.residual[j] -= 0.3 * s.prediction[j];
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.time_varying.has_value());
  EXPECT_EQ(d.time_varying->shape.shape, DriftShape::kStep);
  EXPECT_NEAR(d.time_varying->shape.at, 9.0, 0.4);  // the windows are 0.75 s long
  EXPECT_NEAR(d.time_varying->shape.end - d.time_varying->shape.start, -0.3, 0.03);
}

// A motion like an earthquake's storey drift: 49 sinusoids of one amplitude every 0.1 Hz from
// 0.2 to 5 Hz with random phases (mm), its spectrum broad where a test's spectrum is lines.
Synthetic broadband(double noise) {
  Synthetic out = synthetic(noise);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  std::vector<double> phases(49);
  for (double& p : phases) p = phase(rng);
  for (std::size_t j = 0; j < kSamples; ++j) {
    out.prediction[j] = 0.0;
    for (std::size_t k = 0; k < phases.size(); ++k)
      out.prediction[j] +=
          std::sin(2.0 * std::numbers::pi * (0.2 + 0.1 * k) * out.time[j] + phases[k]);
  }
  return out;
}

// p's rate at every sample (central differences, mm/s).
std::vector<double> rate(const Synthetic& s) {
  std::vector<double> out(kSamples, 0.0);
  for (std::size_t j = 1; j + 1 < kSamples; ++j)
    out[j] = (s.prediction[j + 1] - s.prediction[j - 1]) / (2.0 * kDt);
  return out;
}

// A neighbour's 0.3 mm at 1.2 Hz, a frequency the motion holds as much as any: the residual
// stands out of the motion's spectrum there, so it is another source's period, not the model's
// error on the motion.
TEST(DescribeResidual, APeriodAtAFrequencyTheMotionHoldsTooIsPeriodic) {
  Synthetic s = broadband(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += 0.3 * std::sin(2.0 * std::numbers::pi * 1.2 * s.time[j] + 0.4);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.periodic.has_value());
  EXPECT_NEAR(d.periodic->frequency, 1.2, 0.01);
  EXPECT_NEAR(d.periodic->amplitude, 0.3, 0.015);
}

// A lag the model lacks leaves -tau dp/dt: the motion's own spectrum, no period, and a line over
// the rate, which is the fit's to hold, not a signature of the rate (the loop it draws against p
// is the maps' to read).
TEST(DescribeResidual, AModelsLagOnTheMotionIsNoPeriodAndNoSignatureOfTheRate) {
  Synthetic s = broadband(0.05);
  const std::vector<double> v = rate(s);
  for (std::size_t j = 0; j < kSamples; ++j) s.residual[j] -= 0.002 * v[j];
  const ResidualDescription d = described(s);
  EXPECT_FALSE(d.periodic.has_value());
  EXPECT_FALSE(d.direction && d.direction->of_rate);
  EXPECT_FALSE(d.amplitude && d.amplitude->of_rate);
  EXPECT_FALSE(d.time_varying.has_value());  // a constant lead does not move
}

// A term in quadrature with the model whose size moves (a damper whose oil warms): the measured
// leads the model by 2 ms at the start and lags it by 2 ms at the end, linearly. No ratio to p
// holds it; the trend against p's rate does, with its lead at the start and at the end.
TEST(DescribeResidual, ALeadThatMovesOverTheRecordIsTimeVaryingOfTheRate) {
  Synthetic s = broadband(0.05);
  const std::vector<double> v = rate(s);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += 0.004 * (0.5 - s.time[j] / s.time.back()) * v[j];
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.time_varying.has_value());
  EXPECT_TRUE(d.time_varying->of_rate);
  EXPECT_EQ(d.time_varying->shape.shape, DriftShape::kLinear);
  EXPECT_NEAR(d.time_varying->shape.start, 0.002, 0.0004);
  EXPECT_NEAR(d.time_varying->shape.end, -0.002, 0.0004);
  EXPECT_GT(d.explained, 0.5);
}

// An actuator that lags 4 ms extending and 12 ms retracting, fitted with one 8 ms lag: the
// residual 0.004 |dp/dt| is no function of p but of the direction of motion, the measured
// leading the model by 8 ms more rising than falling.
TEST(DescribeResidual, AnActuatorSlowerOneWayIsTheDirectionOfMotion) {
  Synthetic s = broadband(0.05);
  const std::vector<double> v = rate(s);
  for (std::size_t j = 0; j < kSamples; ++j) s.residual[j] += 0.004 * std::abs(v[j]);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.direction.has_value());
  EXPECT_TRUE(d.direction->of_rate);
  EXPECT_NEAR(d.direction->lead_difference, 0.008, 0.0008);
  EXPECT_FALSE(d.periodic || d.amplitude);
  EXPECT_GT(d.explained, 0.9);
}

// A flow limit: the reading falls short by 2e-5 s^2/mm v|v| at large rates, less the line over
// v a fitted lag takes (least squares): the rate's amplitude, the measured lagging more at the
// fastest.
TEST(DescribeResidual, AReadingShortAtLargeRatesIsTheRatesAmplitude) {
  Synthetic s = broadband(0.05);
  const std::vector<double> v = rate(s);
  double vq = 0.0, vv = 0.0;
  for (double x : v) {
    vq += x * x * std::abs(x);
    vv += x * x;
  }
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] -= 2e-5 * (v[j] * std::abs(v[j]) - vq / vv * v[j]);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.amplitude.has_value());
  EXPECT_TRUE(d.amplitude->of_rate);
  EXPECT_LT(d.amplitude->lead_change, 0.0);
  EXPECT_FALSE(d.periodic || d.direction);
}

}  // namespace
}  // namespace rths::identify
