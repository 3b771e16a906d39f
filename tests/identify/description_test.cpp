// The description of a residual (identify/residual/description.h) on residuals made to hold one
// signature each beside a model's output like a storey's drift: noise alone is not described, a
// sinusoid is periodic at its frequency, a residual of the input's sign or amplitude or of its
// direction is the map's, and a gain that moves over the record is time-varying with its change
// and its shape (a line, a step with its time, an exponential approach).
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

}  // namespace
}  // namespace rths::identify
