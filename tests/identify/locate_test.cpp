// Where a residual lies (identify/residual/locate.h): a residual concentrated in time is located
// in its windows, the largest first, and noise is spread over the record; a residual's band is
// where its power is; a function of a signal explains a residual that depends on it however its
// form, and none on noise.
#include "identify/residual/locate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace rths::identify {
namespace {

constexpr double kDt = 0.001;
constexpr std::size_t kSamples = 15000;  // 15 s: windows of 0.75 s

struct Series {
  std::vector<double> time, residual;
};

Series noise(double sigma, std::uint64_t seed) {
  Series out;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  for (std::size_t j = 0; j < kSamples; ++j) {
    out.time.push_back(static_cast<double>(j) * kDt);
    out.residual.push_back(normal(rng));
  }
  return out;
}

TEST(ResidualWindows, NoiseAloneIsSpreadOverTheRecord) {
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const Series s = noise(0.05, seed);
    EXPECT_TRUE(residual_windows(s.time, s.residual).empty()) << "seed " << seed;
  }
}

// A 5 Hz burst over 6-9 s (windows 8 to 11) on noise: one window span, 6-9 s, holding most of
// the power; a second, weaker burst at 12.0-12.75 s comes second.
TEST(ResidualWindows, BurstsAreLocatedInTheirWindowsLargestFirst) {
  Series s = noise(0.05, 5);
  for (std::size_t j = 0; j < kSamples; ++j) {
    const double t = s.time[j];
    if (t >= 6.0 && t < 9.0) s.residual[j] += 0.5 * std::sin(2.0 * std::numbers::pi * 5.0 * t);
    if (t >= 12.0 && t < 12.75) s.residual[j] += 0.4 * std::sin(2.0 * std::numbers::pi * 5.0 * t);
  }
  const std::vector<ResidualWindow> w = residual_windows(s.time, s.residual);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NEAR(w[0].start, 6.0, kDt);
  EXPECT_NEAR(w[0].end, 9.0, kDt);
  EXPECT_NEAR(w[1].start, 12.0, kDt);
  EXPECT_NEAR(w[1].end, 12.75, kDt);
  // Power: 3 s x 0.125 and 0.75 s x 0.08 against 15 s x 0.0025 of noise: 81 % and 13 %.
  EXPECT_GT(w[0].share, 0.75);
  EXPECT_GT(w[1].share, 0.1);
  EXPECT_LT(w[1].share, w[0].share);
}

// A 12 Hz sinusoid on noise: the peak at 12 Hz and the band around it.
TEST(ResidualBand, TheBandHoldsTheResidualsPower) {
  Series s = noise(0.01, 6);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += std::sin(2.0 * std::numbers::pi * 12.0 * s.time[j]);
  const ResidualBand band = residual_band(s.residual, kDt);
  EXPECT_NEAR(band.peak_hz, 12.0, 0.1);
  EXPECT_LE(band.low_hz, 12.0);
  EXPECT_GE(band.high_hz, 12.0);
  EXPECT_LT(band.high_hz - band.low_hz, 1.0);
}

// The square of x has no straight correlation with x, yet a function of x
// explains it; noise beside x is explained by none.
TEST(CorrelationRatio, AFunctionOfTheSignalExplainsWhatDependsOnIt) {
  const Series x = noise(1.0, 7), n = noise(0.01, 8);
  std::vector<double> r(kSamples);
  for (std::size_t j = 0; j < kSamples; ++j) r[j] = x.residual[j] * x.residual[j] + n.residual[j];
  EXPECT_GT(correlation_ratio(x.residual, r), 0.7);  // x^2 still varies within each of 16 bins
  EXPECT_LT(correlation_ratio(x.residual, n.residual), 0.01);
}

}  // namespace
}  // namespace rths::identify
