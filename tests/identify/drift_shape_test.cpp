// The shape of a value that moves over a record (identify/residual/drift_shape.h), from its
// values in 20 windows of a 15 s record with a little noise: a line stays a line, a step is found
// at its time with its levels, an exponential approach with its time constant; a flat value is a
// line with no change, and too few windows are refused.
#include "identify/residual/drift_shape.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <vector>

namespace rths::identify {
namespace {

struct Windows {
  std::vector<double> time, value;
};

Windows windows(const std::function<double(double)>& truth, double noise, std::uint64_t seed) {
  Windows out;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, noise);
  for (int w = 0; w < 20; ++w) {
    const double t = 0.375 + 0.75 * w;
    out.time.push_back(t);
    out.value.push_back(truth(t) + normal(rng));
  }
  return out;
}

TEST(DriftShape, ALineStaysALineWithItsEnds) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Windows w = windows([](double t) { return 1.0 - 0.02 * t; }, 0.005, seed);
    const ShapeFit fit = fit_shape(w.time, w.value);
    EXPECT_EQ(fit.shape, DriftShape::kLinear) << "seed " << seed;
    EXPECT_NEAR(fit.start, 1.0 - 0.02 * 0.375, 0.01);
    EXPECT_NEAR(fit.end, 1.0 - 0.02 * 14.625, 0.01);
    EXPECT_EQ(fit.at, 0.0);
  }
}

TEST(DriftShape, AStepIsFoundAtItsTimeWithItsLevels) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Windows w = windows([](double t) { return t < 6.2 ? 1.0 : 0.7; }, 0.005, seed);
    const ShapeFit fit = fit_shape(w.time, w.value);
    ASSERT_EQ(fit.shape, DriftShape::kStep) << "seed " << seed;
    EXPECT_NEAR(fit.at, 6.2, 0.375);  // between the windows either side
    EXPECT_NEAR(fit.start, 1.0, 0.01);
    EXPECT_NEAR(fit.end, 0.7, 0.01);
    EXPECT_LT(fit.sse_step, kShapeWins * fit.sse_linear);
  }
}

TEST(DriftShape, AnExponentialApproachHasItsTimeConstant) {
  const auto truth = [](double t) { return 0.6 + 0.4 * std::exp(-(t - 0.375) / 3.0); };
  const Windows w = windows(truth, 0.002, 4);
  const ShapeFit fit = fit_shape(w.time, w.value);
  ASSERT_EQ(fit.shape, DriftShape::kExponential);
  EXPECT_NEAR(fit.at, 3.0, 0.5);
  EXPECT_NEAR(fit.start, 1.0, 0.01);
  EXPECT_NEAR(fit.end, truth(14.625), 0.01);
}

TEST(DriftShape, AFlatValueIsALineWithNoChange) {
  const Windows w = windows([](double) { return 0.5; }, 0.001, 5);
  const ShapeFit fit = fit_shape(w.time, w.value);
  EXPECT_EQ(fit.shape, DriftShape::kLinear);
  EXPECT_NEAR(fit.end - fit.start, 0.0, 0.003);
  EXPECT_EQ(shape_name(fit.shape), "linear");
}

// value_at gives each shape's fitted path between and beyond the windows' centres.
TEST(DriftShape, ValueAtFollowsEachShape) {
  const auto line = [](double t) { return 1.0 - 0.02 * t; };
  const auto step = [](double t) { return t < 6.2 ? 1.0 : 0.7; };
  const auto approach = [](double t) { return 0.6 + 0.4 * std::exp(-(t - 0.375) / 3.0); };
  for (const auto& truth :
       {std::function<double(double)>(line), std::function<double(double)>(step),
        std::function<double(double)>(approach)}) {
    const Windows w = windows(truth, 0.0005, 6);
    const ShapeFit fit = fit_shape(w.time, w.value);
    EXPECT_EQ(fit.first, 0.375);
    EXPECT_EQ(fit.last, 14.625);
    for (double t : {0.0, 2.0, 5.9, 6.5, 11.0, 15.0})
      EXPECT_NEAR(fit.value_at(t), truth(t), 0.005) << shape_name(fit.shape) << " at " << t;
  }
}

TEST(DriftShape, TooFewWindowsAreRefused) {
  const std::vector<double> t{0.0, 1.0, 2.0}, v{1.0, 1.0, 1.0};
  EXPECT_THROW(fit_shape(t, v), std::invalid_argument);
}

}  // namespace
}  // namespace rths::identify
