#include "runtime/node/lag.h"

#include "study/case_link.h"
#include "study/study.h"

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
    study::validate_link_lag(lag(0, 0, 1.5, 0), "nodes[2].send_lag", false, "test");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nodes[2].send_lag.loss"), std::string::npos);
  }
  EXPECT_THROW(study::validate_link_lag(lag(-1, 0, 0, 0), "x", false, "test"),
               std::invalid_argument);
}

config::LinkLag emulated(double drift_rate, double spike_delay, int spike_every, int spike_steps,
                         int drop_first_step, int drop_steps) {
  config::LinkLag l = lag(0.001, 0, 0, 1);
  config::NetworkEmulation& net = *l.mutable_network();
  net.set_drift_rate(drift_rate);
  net.set_spike_delay(spike_delay);
  net.set_spike_every(spike_every);
  net.set_spike_steps(spike_steps);
  net.set_drop_first_step(drop_first_step);
  net.set_drop_steps(drop_steps);
  return l;
}

// The emulated network's drift and spikes delay the commands without being reported: the
// reported lag stays the link's own 1 ms while the release moves.
TEST(LagInjector, NetworkEmulationDelaysCommandsUnreported) {
  LagInjector injector(emulated(0.001, 0.006, 500, 3, 0, 0), 0.001);
  EXPECT_TRUE(injector.active());
  EXPECT_EQ(injector.schedule(0, 100), 1 * kMs + 100'000);  // 1 ms + 0.1 ms of drift at t = 0.1 s
  EXPECT_NEAR(injector.last_delay(), 0.001, 1e-12);
  EXPECT_EQ(injector.schedule(1000 * kMs, 1001), 1007 * kMs + 1'001'000);  // a spike: + 6 ms
  EXPECT_NEAR(injector.last_delay(), 0.001, 1e-12);
  EXPECT_EQ(injector.schedule(2000 * kMs, 1003), 2001 * kMs + 1'003'000);  // after it: none
  EXPECT_EQ(injector.schedule(3000 * kMs), 3001 * kMs);  // not a command: untouched
}

TEST(LagInjector, NetworkEmulationDropsABurstOfCommandsOnly) {
  LagInjector injector(emulated(0, 0, 0, 0, 10, 4), 0.001);
  EXPECT_TRUE(injector.active());
  int dropped = 0;
  for (std::int64_t k = 1; k <= 20; ++k) dropped += injector.schedule(k * kMs, k) ? 0 : 1;
  EXPECT_EQ(dropped, 4);
  for (std::int64_t k = 10; k < 14; ++k) EXPECT_FALSE(injector.schedule(k * kMs, k));
  EXPECT_TRUE(injector.schedule(30 * kMs, 9));
  EXPECT_TRUE(injector.schedule(40 * kMs));  // a heartbeat in the burst's time goes through
}

TEST(ValidateLinkLag, NetworkEmulationOutOfRangeNamesTheField) {
  const auto message = [](const config::LinkLag& l) {
    try {
      study::validate_link_lag(l, "nodes[0].receive_lag", true, "test");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message(emulated(0.001, 0.006, 500, 3, 10, 4)), "");
  EXPECT_NE(message(emulated(2.0, 0, 0, 0, 0, 0)).find("receive_lag.network.drift_rate"),
            std::string::npos);
  EXPECT_NE(message(emulated(0, 0.006, 3, 3, 0, 0)).find("spike_steps = 3 must be below"),
            std::string::npos);
  EXPECT_NE(message(emulated(0, 0, 0, 0, 0, 4)).find("drop_first_step must be >= 1"),
            std::string::npos);
  EXPECT_NE(message(emulated(0, 0, 0, 0, 1, -2)).find("network.drop_steps"), std::string::npos);
  EXPECT_NE(message(emulated(0, -0.001, 10, 1, 0, 0)).find("network.spike_delay"),
            std::string::npos);
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

// A case's link in process (core/link_answers.h) draws what a node injecting the same LinkLag
// draws: message for message, the same release or the same loss, so a case's `link` and a
// node's lag mean one network.
TEST(LagInjector, TheInProcessLinkReleasesWhatTheNodeInjects) {
  config::LinkLag spec = lag(0.030, 0.0025, 0.05, 521);
  spec.mutable_network()->set_drift_rate(0.0005);
  spec.mutable_network()->set_spike_delay(0.004);
  spec.mutable_network()->set_spike_every(200);
  spec.mutable_network()->set_spike_steps(20);
  spec.mutable_network()->set_drop_first_step(3000);
  spec.mutable_network()->set_drop_steps(40);
  constexpr double kDt = 0.001;
  LagInjector node(spec, kDt);
  core::LinkWayLag in_process(study::link_way(spec), kDt);
  std::size_t lost = 0;
  for (std::int64_t k = 1; k <= 10000; ++k) {
    const std::int64_t sent = k * kMs;
    const std::optional<std::int64_t> injected = node.schedule(sent, k);
    ASSERT_EQ(injected, in_process.release(sent, k)) << "step " << k;
    lost += injected ? 0 : 1;
  }
  EXPECT_GT(lost, 400u);  // 5 % of 10,000 and the 40 dropped: both paths were taken
}

}  // namespace
}  // namespace rths::runtime
