#include "runtime/lag.h"

#include <gtest/gtest.h>

namespace rths::runtime {
namespace {

constexpr std::int64_t kMs = 1'000'000;

config::LinkLag lag(double delay, double jitter, double loss, std::uint64_t seed) {
  config::LinkLag l;
  l.set_one_way_delay(delay);
  l.set_jitter(jitter);
  l.set_loss(loss);
  l.set_seed(seed);
  return l;
}

TEST(LagInjector, ConstantDelayShiftsEveryMessage) {
  LagInjector injector(lag(0.010, 0, 0, 1));
  EXPECT_TRUE(injector.active());
  EXPECT_EQ(injector.schedule(100 * kMs), 110 * kMs);
  EXPECT_DOUBLE_EQ(injector.last_delay(), 0.010);
}

TEST(LagInjector, JitterIsReproducibleFromItsSeedAndNeverReorders) {
  LagInjector a(lag(0.002, 0.003, 0, 42)), b(lag(0.002, 0.003, 0, 42));
  std::int64_t previous = 0;
  for (int i = 0; i < 1000; ++i) {
    const auto ra = a.schedule(i * kMs);
    ASSERT_EQ(ra, b.schedule(i * kMs));
    ASSERT_GE(*ra, i * kMs);   // never before it arrived
    ASSERT_GE(*ra, previous);  // FIFO
    previous = *ra;
  }
}

TEST(LagInjector, LossDropsAboutTheRequestedFraction) {
  LagInjector injector(lag(0, 0, 0.1, 7));
  int lost = 0;
  for (int i = 0; i < 10000; ++i) lost += injector.schedule(i * kMs) ? 0 : 1;
  EXPECT_NEAR(lost / 10000.0, 0.1, 0.015);
}

TEST(LagInjector, InactiveWhenAllZero) { EXPECT_FALSE(LagInjector(config::LinkLag{}).active()); }

TEST(ValidateLinkLag, NamesTheBadField) {
  try {
    validate_link_lag(lag(0, 0, 1.5, 0), "nodes[2].send_lag");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nodes[2].send_lag.loss"), std::string::npos);
  }
  EXPECT_THROW(validate_link_lag(lag(-1, 0, 0, 0), "x"), std::invalid_argument);
}

TEST(Summarize, MedianPercentileAndMax) {
  std::vector<double> lags;
  for (int i = 1; i <= 100; ++i) lags.push_back(i * 1e-3);
  const LagSummary s = summarize(lags);
  EXPECT_EQ(s.count, 100u);
  EXPECT_DOUBLE_EQ(s.median, 0.0505);  // textbook median, as core::median: not the upper middle
  EXPECT_DOUBLE_EQ(s.p99, 0.100);
  EXPECT_DOUBLE_EQ(s.max, 0.100);
  EXPECT_NEAR(s.mean, 0.0505, 1e-12);
  EXPECT_EQ(summarize({}).count, 0u);
}

}  // namespace
}  // namespace rths::runtime
