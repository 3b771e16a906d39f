// identify/run/clock_offset: the two hosts' clock offset from one-way stamps, on stamps made by
// hand with a known offset, path and injection.
#include "identify/run/clock_offset.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace rths::identify {
namespace {

struct Stamps {
  std::vector<double> down, up;
};

// One-way times of n answers: a path of `path` s each way with 50 us of jitter, `injected` s
// injected each way, the node's clock `offset` s ahead of the coordinator's.
Stamps stamps(std::size_t n, double path, double injected, double offset) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> jitter(0.0, 50e-6);
  Stamps s;
  for (std::size_t i = 0; i < n; ++i) {
    s.down.push_back(path + injected + offset + jitter(rng));
    s.up.push_back(path + injected - offset + jitter(rng));
  }
  return s;
}

TEST(ClockOffset, AHostsOffsetIsMeasuredWithinAFewMicrosecondsAndNamed) {
  const Stamps s = stamps(2000, 0.3e-3, 2e-3, 2.4e-3);
  const auto c = clock_offset(s.down, s.up, 2e-3, 2e-3);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->offset, 2.4e-3, 10e-6);
  EXPECT_TRUE(c->named);
  EXPECT_NE(c->detail.find("+2.4 ms"), std::string::npos) << c->detail;
  EXPECT_NE(c->detail.find("negative one-way time"), std::string::npos) << c->detail;
}

TEST(ClockOffset, OneHostOrSynchronisedClocksNameNothing) {
  const Stamps s = stamps(2000, 0.05e-3, 7e-3, 0.0);
  const auto c = clock_offset(s.down, s.up, 7e-3, 7e-3);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->offset, 0.0, 10e-6);
  EXPECT_FALSE(c->named) << c->detail;
}

// Below the 0.5 ms threshold an offset still shows when it makes a way's time negative.
TEST(ClockOffset, ASmallOffsetThatMakesAWayNegativeIsNamed) {
  const Stamps s = stamps(500, 0.05e-3, 0.0, 0.3e-3);
  const auto c = clock_offset(s.down, s.up, 0.0, 0.0);
  ASSERT_TRUE(c.has_value());
  EXPECT_LT(c->up_median, -kNegativeTolerance);
  EXPECT_TRUE(c->named);
}

TEST(ClockOffset, TooFewAnswersGiveNoEstimate) {
  const Stamps s = stamps(kMinClockSamples - 1, 0.05e-3, 0.0, 3e-3);
  EXPECT_FALSE(clock_offset(s.down, s.up, 0.0, 0.0).has_value());
}

}  // namespace
}  // namespace rths::identify
