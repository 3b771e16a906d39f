// A lag that grows in time read from what a constant-lag model leaves
// (identify/residual/delay_growth.h): a force read through a clock 600 ppm slow, modelled with its
// mean lag, gives back the growth and no miss of the mean; the same force read with a constant lag
// the model holds gives none, and a residual of noise alone gives none.
#include "identify/residual/delay_growth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace rths::identify {
namespace {

constexpr double kDt = 0.001;
constexpr std::size_t kSamples = 15000;

// A storey force under a ground motion (N): several frequencies, an envelope.
double force(double t) {
  const double w = 2.0 * std::numbers::pi;
  return (0.5 + 0.5 * std::sin(w * 0.05 * t)) *
         (800.0 * std::sin(w * 1.9 * t) + 300.0 * std::sin(w * 0.7 * t + 1.0));
}

struct Read {
  std::vector<double> time, residual, prediction;
};

// The force read late by lag(t), against the model reading it late by `model_lag`; noise 0.5 N.
Read read(double (*lag)(double), double model_lag) {
  Read out;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (std::size_t j = 0; j < kSamples; ++j) {
    const double t = static_cast<double>(j) * kDt;
    out.time.push_back(t);
    out.prediction.push_back(force(t - model_lag));
    out.residual.push_back(force(t - lag(t)) + noise(rng) - out.prediction.back());
  }
  return out;
}

TEST(DelayGrowth, AClockRunningSlowIsALagGrowingAtItsRate) {
  const Read r = read([](double t) { return 600e-6 * t; }, 600e-6 * 7.5);
  const auto g = delay_growth(r.time, r.residual, r.prediction, kDt);
  ASSERT_TRUE(g.has_value());
  EXPECT_NEAR(g->growth, 600e-6, 30e-6);
  EXPECT_NEAR(g->mean_miss, 0.0, 2e-4);
  EXPECT_GT(g->explained, 0.9);
}

TEST(DelayGrowth, AConstantLagTheModelHoldsAndNoiseAloneGrowNothing) {
  const Read held = read([](double) { return 0.007; }, 0.007);
  EXPECT_FALSE(delay_growth(held.time, held.residual, held.prediction, kDt).has_value());
  Read noise = held;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal(0.0, 5.0);
  for (double& x : noise.residual) x = normal(rng);
  EXPECT_FALSE(delay_growth(noise.time, noise.residual, noise.prediction, kDt).has_value());
}

}  // namespace
}  // namespace rths::identify
