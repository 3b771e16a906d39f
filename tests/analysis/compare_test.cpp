#include "analysis/common/compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/metrics.h"

namespace rths::analysis {
namespace {

core::SimulationResult result_of(const std::vector<std::vector<double>>& floors) {
  core::SimulationResult r;
  r.dt = 0.01;
  const auto steps = static_cast<Eigen::Index>(floors.front().size());
  r.displacement = core::Mat::Zero(steps, static_cast<Eigen::Index>(floors.size()));
  for (std::size_t f = 0; f < floors.size(); ++f) {
    for (Eigen::Index k = 0; k < steps; ++k)
      r.displacement(k, static_cast<Eigen::Index>(f)) = floors[f][k];
  }
  r.time.resize(static_cast<std::size_t>(steps));
  return r;
}

TEST(Compare, NrmseIsAPercentageOfTheCoreMeasure) {
  const std::vector<double> reference = {0.0, 1.0, -2.0, 1.5, -0.5};
  const std::vector<double> lagged = {0.0, 1.2, -2.5, 1.4, -0.2};
  const Comparison c = compare(reference, lagged, false);
  EXPECT_DOUBLE_EQ(c.nrmse_pct, 100.0 * core::nrmse(reference, lagged));
  EXPECT_DOUBLE_EQ(c.paper_eq2_as_printed, core::paper_eq2(reference, lagged));
  EXPECT_DOUBLE_EQ(c.peak_m, 2.5);
  EXPECT_DOUBLE_EQ(c.peak_reference_m, 2.0);
  EXPECT_NEAR(c.peak_error_m, 0.5, 1e-15);
  EXPECT_FALSE(c.diverged);
  EXPECT_EQ(c.to_json().at("nrmse_pct"), c.nrmse_pct);
}

// The errors a summary leads with: against the reference's own peak and RMS, over the steps both
// have; a case shorter than its reference does not cover it.
TEST(Compare, PeakAndRmsErrorsAgainstTheReferencesOwnAndTheStepsCovered) {
  const std::vector<double> reference = {0.0, 2.0, -4.0, 2.0};
  const std::vector<double> lagged = {0.0, 2.5, -4.0, 1.5};
  const Comparison c = compare(reference, lagged, false);
  EXPECT_DOUBLE_EQ(c.peak_error_pct, 12.5);
  EXPECT_DOUBLE_EQ(c.rms_error_pct, 100.0 * std::sqrt(0.5 / 24.0));
  EXPECT_EQ(c.reference_steps, 4u);
  EXPECT_TRUE(c.covers_reference());
  EXPECT_EQ(c.to_json().at("peak_error_pct"), c.peak_error_pct);
  const Comparison held = compare(reference, std::vector<double>{0.0, 2.0}, true);
  EXPECT_FALSE(held.covers_reference());
  EXPECT_EQ(held.steps_compared, 2u);
  EXPECT_DOUBLE_EQ(held.peak_error_pct,
                   0.0);  // over its two steps: a report must not show it alone
}

TEST(Compare, GrowthPastTheReferenceOrAnEarlyStopIsDivergence) {
  const std::vector<double> reference = {0.0, 0.01, -0.01, 0.01};
  EXPECT_TRUE(compare(reference, std::vector<double>{0.0, 0.02, -0.5, 2.0}, false).diverged);
  EXPECT_TRUE(compare(reference, std::vector<double>{0.0, 0.01}, true).diverged);  // stopped early
  EXPECT_EQ(compare(reference, std::vector<double>{0.0, 0.01}, true).steps_compared, 2u);
  EXPECT_FALSE(compare(reference, std::vector<double>{0.0, 0.03, -0.02, 0.01}, false).diverged);
}

// `rths run`'s verdict beyond the 10x rule: past the critical delay, an envelope that grows
// exponentially (here 9x over the record, under the 10x rule; 2.1x over the fitted last third)
// is diverging; the same history inside the critical delay, or a decaying one past it, is not.
TEST(Compare, PastTheCriticalDelayAGrowingEnvelopeIsDiverging) {
  const double dt = 0.01, period = 0.5;
  std::vector<double> growing, decaying;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * dt, wave = std::sin(2.0 * M_PI * t / period);
    growing.push_back(std::exp(std::log(9.0) * t / 20.0) * wave);
    decaying.push_back(std::exp(-0.2 * t) * wave);
  }
  EXPECT_TRUE(diverging(growing, dt, period, true));
  EXPECT_FALSE(diverging(growing, dt, period, false));
  EXPECT_FALSE(diverging(decaying, dt, period, true));
  EXPECT_FALSE(diverging(growing, dt, 0.0, true));  // no period to fit at
  EXPECT_FALSE(compare(decaying, growing, false).diverged);
}

TEST(Compare, TheResponseIsNamed) {
  const auto reference = result_of({{0, 1, 0, -1}, {0, 2, 0, -2}});
  const auto lagged = result_of({{0, 1, 0, -1}, {0, 2.5, 0, -2}});
  const Comparison first = compare(reference, lagged, ResponseSpec::floor(1));
  EXPECT_EQ(first.response, "floor 1");
  EXPECT_DOUBLE_EQ(first.nrmse_pct, 0.0);
  const Comparison top = compare(reference, lagged, ResponseSpec::top_floor(2));
  EXPECT_EQ(top.response, "floor 2");
  EXPECT_GT(top.nrmse_pct, 0.0);
  const Comparison worst = compare(reference, lagged, ResponseSpec::peak_over_floors());
  EXPECT_EQ(worst.response, "peak over floors");
  EXPECT_DOUBLE_EQ(worst.nrmse_pct, top.nrmse_pct);
  EXPECT_DOUBLE_EQ(worst.peak_m, 2.5);
  EXPECT_THROW(compare(reference, lagged, ResponseSpec::floor(3)), std::invalid_argument);
  EXPECT_THROW(ResponseSpec::floor(0), std::invalid_argument);
}

}  // namespace
}  // namespace rths::analysis
