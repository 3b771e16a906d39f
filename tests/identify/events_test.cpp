// Events located in time (identify/residual/events.h) on a made channel: a reading that follows a
// model's output like a storey's drift, with a residual the model leaves in proportion to the
// motion and the sensor's noise on a 16-bit converter. Noise alone holds no event; a held reading,
// spikes, a burst of a few seconds, an offset that steps from some time on and a force that falls
// against the model from some time on are each found with their times, their kind and their size;
// a steady ripple and a short burst at the record's end are none; bad input is refused naming the problem.
#include "identify/residual/events.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace rths::identify {
namespace {

constexpr double kDt = 0.001;
constexpr std::size_t kSamples = 20000;  // 20 s
constexpr double kNoise = 0.5;           // N RMS, the sensor's
constexpr double kQuantum = 20000.0 / 32768.0;

struct Channel {
  std::vector<double> time, reading, prediction;
};

double converted(double x) { return std::round(x / kQuantum) * kQuantum; }

// The prediction: ~2 kN of force under an envelope; the reading 0.2 % off it and noisy.
Channel channel(std::uint64_t seed) {
  Channel out;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, kNoise);
  for (std::size_t j = 0; j < kSamples; ++j) {
    const double t = static_cast<double>(j) * kDt, w = 2.0 * std::numbers::pi;
    const double envelope = 0.3 + 0.7 * std::exp(-std::pow((t - 7.0) / 4.0, 2.0));
    const double p = envelope * (2000.0 * std::sin(w * 1.9 * t) + 800.0 * std::sin(w * 3.3 * t));
    out.time.push_back(t);
    out.prediction.push_back(p);
    out.reading.push_back(converted(1.002 * p + normal(rng)));
  }
  return out;
}

std::vector<ResidualEvent> events_of(const Channel& c) {
  return find_events(c.time, c.reading, c.prediction, kDt, kNoise);
}

std::vector<ResidualEvent> of_kind(const std::vector<ResidualEvent>& all, EventKind kind) {
  std::vector<ResidualEvent> out;
  std::copy_if(all.begin(), all.end(), std::back_inserter(out),
               [&](const ResidualEvent& e) { return e.kind == kind; });
  std::sort(out.begin(), out.end(),
            [](const ResidualEvent& a, const ResidualEvent& b) { return a.start < b.start; });
  return out;
}

TEST(ResidualEvents, NoiseAndAModelErrorThatFollowsTheMotionHoldNoEvent) {
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const std::vector<ResidualEvent> e = events_of(channel(seed));
    EXPECT_TRUE(e.empty()) << "seed " << seed << ": " << event_name(e.front().kind) << " at "
                           << e.front().start;
  }
}

// A pump's 100 N ripple at 7 Hz over the whole record, strong beside the quiet start: steady, so
// no event (a record's own level is not a moment of it).
TEST(ResidualEvents, ASteadyRippleOverTheRecordIsNoEvent) {
  Channel c = channel(10);
  for (std::size_t j = 0; j < kSamples; ++j)
    c.reading[j] += 100.0 * std::sin(2.0 * std::numbers::pi * 7.0 * c.time[j]);
  const std::vector<ResidualEvent> e = events_of(c);
  EXPECT_TRUE(e.empty()) << event_name(e.front().kind) << " at " << e.front().start;
}

// The reading holds its value over 6.0-6.3 s while the force moves on.
TEST(ResidualEvents, AHeldReadingIsFoundWithItsTimes) {
  Channel c = channel(5);
  for (std::size_t j = 6001; j < 6300; ++j) c.reading[j] = c.reading[6000];
  const auto held = of_kind(events_of(c), EventKind::kHeldSample);
  ASSERT_EQ(held.size(), 1u);
  EXPECT_NEAR(held[0].start, 6.0, kDt);
  EXPECT_NEAR(held[0].end, 6.299, kDt);
  EXPECT_GT(held[0].size, 100.0);  // N RMS: the force moved by hundreds of N meanwhile
}

// 200 N spikes on single samples at 3.1, 9.45 and 15.0 s, and one of two samples at 12.2 s.
TEST(ResidualEvents, SpikesAreFoundEachAtItsTime) {
  Channel c = channel(6);
  for (std::size_t j : {3100u, 9450u, 15000u, 12200u, 12201u}) c.reading[j] += 200.0;
  const auto spikes = of_kind(events_of(c), EventKind::kSpike);
  ASSERT_EQ(spikes.size(), 4u);
  const double at[] = {3.1, 9.45, 12.2, 15.0};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(spikes[i].start, at[i], 1.5 * kDt) << i;
    EXPECT_NEAR(spikes[i].size, 200.0, 10.0) << i;
  }
}

// A 30 N rattle at 25 Hz over 11-13.5 s: a burst there, and nothing else.
TEST(ResidualEvents, ABurstIsLocatedInItsWindow) {
  Channel c = channel(7);
  for (std::size_t j = 11000; j < 13500; ++j)
    c.reading[j] += 30.0 * std::sin(2.0 * std::numbers::pi * 25.0 * c.time[j]);
  const std::vector<ResidualEvent> all = events_of(c);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].kind, EventKind::kBurst);
  EXPECT_NEAR(all[0].start, 11.0, 0.1);  // blocks of 50 ms
  EXPECT_NEAR(all[0].end, 13.5, 0.1);
  EXPECT_GT(all[0].share, 0.8);
}

// The load cell's offset jumps by 25 N at 12 s and stays: a step change there of that size.
TEST(ResidualEvents, AnOffsetThatStepsIsAStepChangeWithItsSize) {
  Channel c = channel(8);
  for (std::size_t j = 12000; j < kSamples; ++j) c.reading[j] += 25.0;
  const std::vector<ResidualEvent> all = events_of(c);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].kind, EventKind::kStepChange);
  EXPECT_NEAR(all[0].start, 12.0, 0.1);
  EXPECT_NEAR(all[0].size, 25.0, 2.0);
}

// The force falls to 70 % of the model's from 12 s on: a capacity drop there, of -30 %.
TEST(ResidualEvents, AForceThatFallsAgainstTheModelFromAMomentIsACapacityDrop) {
  Channel c = channel(11);
  for (std::size_t j = 12000; j < kSamples; ++j) c.reading[j] = converted(c.reading[j] * 0.7);
  const std::vector<ResidualEvent> all = events_of(c);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].kind, EventKind::kCapacityDrop);
  EXPECT_NEAR(all[0].start, 12.0, 0.1);
  EXPECT_NEAR(all[0].size, -0.3, 0.02);
}

// A burst in the record's last second is a correct model's edge, not an event.
TEST(ResidualEvents, AShortBurstAtTheRecordsEndIsNoEvent) {
  Channel c = channel(12);
  for (std::size_t j = 19300; j < kSamples; ++j)
    c.reading[j] += 30.0 * std::sin(2.0 * std::numbers::pi * 25.0 * c.time[j]);
  EXPECT_TRUE(events_of(c).empty());
}

TEST(ResidualEvents, BadInputIsRefusedNamingIt) {
  const Channel c = channel(9);
  const std::vector<double> short_time(c.time.begin(), c.time.begin() + 10);
  EXPECT_THROW(find_events(short_time, c.reading, c.prediction, kDt, kNoise),
               std::invalid_argument);
  EXPECT_THROW(find_events(c.time, c.reading, c.prediction, 0.0, kNoise), std::invalid_argument);
  EXPECT_THROW(find_events(c.time, c.reading, c.prediction, kDt, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace rths::identify
