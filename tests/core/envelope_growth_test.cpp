#include "core/envelope_growth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace rths::core {
namespace {

// exp(rate t) sin(2 pi t / period) over `duration` s at dt.
std::vector<double> oscillation(double rate, double period, double duration, double dt) {
  std::vector<double> u(static_cast<std::size_t>(std::llround(duration / dt)));
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double t = static_cast<double>(k) * dt;
    u[k] = std::exp(rate * t) * std::sin(2.0 * std::numbers::pi * t / period);
  }
  return u;
}

TEST(EnvelopeGrowth, AGrowingOscillationGivesItsRateAndDoublingTime) {
  const auto g = envelope_growth(oscillation(0.35, 0.3, 30.0, 0.001), 0.001, 0.3);
  ASSERT_TRUE(g.has_value());
  EXPECT_NEAR(g->rate, 0.35, 0.35 * 0.01);
  EXPECT_NEAR(g->doubling_time, std::numbers::ln2 / 0.35, 0.02);
  EXPECT_GT(g->r_squared, 0.999);
  EXPECT_EQ(g->windows, 33);  // the last third: 10 s of 0.3 s windows
  EXPECT_TRUE(g->grows());
}

TEST(EnvelopeGrowth, ADecayingOrSteadyOscillationDoesNotGrow) {
  const auto decaying = envelope_growth(oscillation(-0.6, 0.5, 20.0, 0.001), 0.001, 0.5);
  ASSERT_TRUE(decaying.has_value());
  EXPECT_NEAR(decaying->rate, -0.6, 0.006);
  EXPECT_FALSE(decaying->grows());
  EXPECT_TRUE(std::isinf(decaying->doubling_time));
  const auto steady = envelope_growth(oscillation(0.0, 0.5, 20.0, 0.001), 0.001, 0.5);
  ASSERT_TRUE(steady.has_value());
  EXPECT_NEAR(steady->rate, 0.0, 1e-3);
  EXPECT_FALSE(steady->grows());
}

// Growth too slow to double over the fitted span, and a late burst that the fit does not explain,
// are not exponential growth.
TEST(EnvelopeGrowth, SlowGrowthOrALateBurstIsNotExponentialGrowth) {
  const auto slow = envelope_growth(oscillation(0.01, 0.5, 30.0, 0.001), 0.001, 0.5);
  ASSERT_TRUE(slow.has_value());
  EXPECT_GT(slow->rate, 0.0);
  EXPECT_FALSE(slow->grows());  // 0.01/s over 10 s: x1.1
  std::vector<double> burst = oscillation(-0.3, 0.5, 30.0, 0.001);
  for (std::size_t k = 25000; k < 26000; ++k) burst[k] *= 400.0;  // one strong pulse at 25 s
  const auto late = envelope_growth(burst, 0.001, 0.5);
  ASSERT_TRUE(late.has_value());
  EXPECT_LT(late->r_squared, EnvelopeGrowth::kMinRSquared);
  EXPECT_FALSE(late->grows());
}

TEST(EnvelopeGrowth, TooShortOrNotFiniteHasNoFit) {
  EXPECT_FALSE(envelope_growth(oscillation(0.3, 1.0, 5.0, 0.01), 0.01, 1.0).has_value());
  std::vector<double> u = oscillation(0.3, 0.3, 30.0, 0.001);
  u.back() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(envelope_growth(u, 0.001, 0.3).has_value());
  EXPECT_FALSE(envelope_growth(std::vector<double>(30000, 0.0), 0.001, 0.3).has_value());
  EXPECT_THROW(envelope_growth(u, 0.0, 0.3), std::invalid_argument);
  EXPECT_THROW(envelope_growth(u, 0.001, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
