#include "core/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace rths::core {
namespace {

TEST(MedianAbs, OddEvenAndSigns) {
  EXPECT_DOUBLE_EQ(median_abs(std::vector<double>{-3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(median_abs(std::vector<double>{4.0, -1.0, 2.0, -10.0}), 3.0);
  EXPECT_DOUBLE_EQ(median_abs(std::vector<double>{-5.0}), 5.0);
  EXPECT_THROW(median_abs(std::vector<double>{}), std::invalid_argument);
}

TEST(Median, TextbookMiddleOrMeanOfTheTwoMiddle) {
  EXPECT_DOUBLE_EQ(median({5.0, 1.0, 3.0}), 3.0);
  EXPECT_DOUBLE_EQ(median({4.0, 1.0, 2.0, 10.0}), 3.0);  // not 4 (the upper middle)
  EXPECT_DOUBLE_EQ(median({-2.0, -1.0}), -1.5);
  EXPECT_THROW(median({}), std::invalid_argument);
}

TEST(MeanAndSpread, HandComputedValues) {
  const std::vector<double> x = {2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0};
  EXPECT_DOUBLE_EQ(mean(x), 5.0);
  EXPECT_DOUBLE_EQ(standard_deviation(x), 2.0);
  EXPECT_DOUBLE_EQ(sample_standard_deviation(x), std::sqrt(32.0 / 7.0));
  EXPECT_DOUBLE_EQ(standard_deviation(std::vector<double>{-3.0}), 0.0);
  EXPECT_THROW(mean(std::vector<double>{}), std::invalid_argument);
  EXPECT_THROW(standard_deviation(std::vector<double>{}), std::invalid_argument);
  EXPECT_THROW(sample_standard_deviation(std::vector<double>{1.0}), std::invalid_argument);
}

TEST(RelativeErrors, AgainstTheReferencesOwnPeakAndRms) {
  const std::vector<double> reference = {0.0, 2.0, -4.0, 2.0};
  const std::vector<double> compared = {0.0, 2.5, -4.0, 1.5};
  EXPECT_DOUBLE_EQ(relative_peak_error_pct(reference, compared), 100.0 * 0.5 / 4.0);
  EXPECT_DOUBLE_EQ(relative_rms_error_pct(reference, compared),
                   100.0 * std::sqrt(0.5 / 24.0));  // sum e^2 = 0.5, sum u_ref^2 = 24
  EXPECT_THROW(relative_peak_error_pct(reference, std::vector<double>{1.0}), std::invalid_argument);
}

// A record that ends in long near-zero motion makes the median-normalised NRMSE explode; the
// errors against the reference's peak and RMS stay what the curves show: a miss of 4 % of the
// peak everywhere reads at most 5 %.
TEST(RelativeErrors, AQuietTailDoesNotInflateThem) {
  std::vector<double> reference, compared;
  for (int k = 0; k < 4000; ++k) {
    const double strong = k < 1000 ? std::sin(0.05 * k) : 1e-4 * std::sin(0.05 * k);
    reference.push_back(strong);
    compared.push_back(strong + 0.04 * (k < 1000 ? std::cos(0.05 * k) : 0.0));
  }
  EXPECT_GT(100.0 * nrmse(reference, compared), 100.0);
  EXPECT_LE(relative_peak_error_pct(reference, compared), 5.0 + 1e-9);
  EXPECT_LE(relative_rms_error_pct(reference, compared), 5.0 + 1e-9);
}

TEST(GrewPastReference, OrderOfMagnitudeOrNotFinite) {
  EXPECT_FALSE(grew_past_reference(0.0136, 0.05));  // 3.7x: a lagged but stable response
  EXPECT_TRUE(grew_past_reference(0.0136, 2.229));  // sdof --delay 0.01 at alpha = 1: 164x
  EXPECT_TRUE(grew_past_reference(0.0136, std::numeric_limits<double>::quiet_NaN()));
  EXPECT_TRUE(grew_past_reference(0.0136, std::numeric_limits<double>::infinity()));
}

TEST(PeakAbs, NanPropagates) {
  EXPECT_DOUBLE_EQ(peak_abs(std::vector<double>{1.0, -4.0, 2.0}), 4.0);
  EXPECT_TRUE(std::isnan(peak_abs(std::vector<double>{1.0, std::nan(""), 2.0})));
}

TEST(ErrorMeasures, HandComputedValues) {
  const std::vector<double> reference{1.0, -2.0, 3.0, -4.0};
  const std::vector<double> compared{1.5, -2.0, 2.0, -4.0};
  // e = {0.5, 0, -1, 0}: sum e^2 = 1.25, median|ref| = 2.5.
  EXPECT_DOUBLE_EQ(paper_eq2(reference, compared), std::sqrt(1.25) / 4.0 / 2.5);
  EXPECT_DOUBLE_EQ(nrmse(reference, compared), std::sqrt(1.25 / 4.0) / 2.5);
  EXPECT_DOUBLE_EQ(peak_error(reference, compared), 1.0);
  EXPECT_DOUBLE_EQ(j2_tracking(reference, compared), 100.0 * std::sqrt(1.25 / 30.0));
  EXPECT_DOUBLE_EQ(j3_peak_tracking(reference, compared), 100.0 * 1.0 / 4.0);
  EXPECT_DOUBLE_EQ(nrmse(reference, reference), 0.0);
}

TEST(ErrorMeasures, RejectEmptyAndMismatchedInputs) {
  const std::vector<double> three{1.0, 2.0, 3.0}, two{1.0, 2.0}, none;
  EXPECT_THROW(paper_eq2(three, two), std::invalid_argument);
  EXPECT_THROW(nrmse(none, none), std::invalid_argument);
  EXPECT_THROW(peak_error(three, two), std::invalid_argument);
  EXPECT_THROW(j1_delay(three, two, 0.01, 0.1), std::invalid_argument);
  EXPECT_THROW(j2_tracking(none, none), std::invalid_argument);
  EXPECT_THROW(j3_peak_tracking(two, three), std::invalid_argument);
}

// The same continuous error sampled twice as finely: N doubles, the RMS stays, so the paper's
// Eq. 2 falls by sqrt(2) while NRMSE does not move (to the sampling of one period).
TEST(PaperEq2, DependsOnTheNumberOfSamplesNrmseDoesNot) {
  const auto reference = [](double t) { return std::sin(2.0 * std::numbers::pi * t); };
  const auto compared = [](double t) {
    return 1.1 * std::sin(2.0 * std::numbers::pi * t) + 0.05 * std::cos(7.0 * t);
  };
  const auto measures = [&](double dt) {
    std::vector<double> r, c;
    for (int i = 0; i < static_cast<int>(std::round(20.0 / dt)); ++i) {
      r.push_back(reference(i * dt));
      c.push_back(compared(i * dt));
    }
    return std::pair{paper_eq2(r, c), nrmse(r, c)};
  };
  const auto [eq2_coarse, nrmse_coarse] = measures(0.01);
  const auto [eq2_fine, nrmse_fine] = measures(0.005);
  EXPECT_NEAR(eq2_coarse / eq2_fine, std::sqrt(2.0), 0.01);
  EXPECT_NEAR(nrmse_fine / nrmse_coarse, 1.0, 0.01);
}

class J1Delay : public ::testing::TestWithParam<double> {};

TEST_P(J1Delay, RecoversNonIntegerSampleDelayOfASine) {
  constexpr double kDt = 1e-3;
  const double delay_samples = GetParam();
  const double delay = delay_samples * kDt;
  constexpr double kFrequency = 2.0;  // 500 samples per period
  std::vector<double> target, measured;
  for (int i = 0; i < 4870; ++i) {  // 9.74 periods: not whole, on purpose
    const double t = i * kDt;
    target.push_back(std::sin(2.0 * std::numbers::pi * kFrequency * t));
    measured.push_back(std::sin(2.0 * std::numbers::pi * kFrequency * (t - delay)));
  }
  EXPECT_NEAR(j1_delay(target, measured, kDt, 0.05), delay, 0.01 * kDt);
  // Swapping the roles turns the lag into a lead.
  EXPECT_NEAR(j1_delay(measured, target, kDt, 0.05), -delay, 0.01 * kDt);
}

INSTANTIATE_TEST_SUITE_P(Lags, J1Delay, ::testing::Values(0.0, 3.4, 12.75, -6.3));

TEST(J1Delay, RejectsBadStepAndLag) {
  const std::vector<double> x{1.0, 2.0, 3.0};
  EXPECT_THROW(j1_delay(x, x, 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(j1_delay(x, x, 0.01, -0.1), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
