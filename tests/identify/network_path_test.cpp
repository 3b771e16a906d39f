// The network path of a link from its answers: each undeclared effect named (drifting delay,
// periodic spikes, a burst of lost answers, an injection other than declared), clean answers
// giving none, and a link with too few answers refused naming its node.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>

#include "identify/run/network_path.h"

namespace rths::identify {
namespace {

constexpr double kDt = 1.0 / 1024.0;
constexpr std::size_t kAnswers = 10240;  // 10 s

// Answers of a healthy link: every step answered at once, 0.3 ms of transport with 40 us of
// Gaussian jitter on top of the injected 2 ms.
LinkAnswers clean_link(std::uint64_t seed = 1) {
  LinkAnswers a;
  a.node_id = 2;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> jitter(0.0, 40e-6);
  for (std::size_t i = 0; i < kAnswers; ++i) {
    a.time.push_back(static_cast<double>(i + 1) * kDt);
    a.answered_step.push_back(static_cast<std::int64_t>(i + 1));
    a.injected.push_back(0.002);
    a.round_trip.push_back(0.002 + 0.0003 + jitter(rng));
  }
  return a;
}

DeclaredLink declared_2ms() { return {0.002, 0.0, 0.0}; }

std::set<std::string> names(const NetworkPath& path) {
  std::set<std::string> out;
  for (const auto& e : path.effects) out.insert(e.name);
  return out;
}

TEST(NetworkPath, ACleanLinkNamesNothingAndMeasuresItsBiasAndJitter) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const NetworkPath path = identify_network_path(clean_link(seed), declared_2ms(), kDt);
    EXPECT_TRUE(path.effects.empty()) << path.effects.front().name;
    EXPECT_NEAR(path.bias, 0.0003, 5e-6);
    EXPECT_NEAR(path.jitter, 40e-6, 5e-6);
    EXPECT_EQ(path.lost, 0u);
    EXPECT_EQ(path.late, 0u);
  }
}

TEST(NetworkPath, ADriftingDelayIsNamedWithItsRange) {
  LinkAnswers a = clean_link();
  for (std::size_t i = 0; i < kAnswers; ++i) a.round_trip[i] += 0.003 * a.time[i] / 10.0;
  const NetworkPath path = identify_network_path(a, declared_2ms(), kDt);
  ASSERT_EQ(names(path), std::set<std::string>{"drifting delay"});
  EXPECT_NEAR(path.drift_range, 0.003, 3e-4);
  EXPECT_LT(path.effects[0].heldout_after, 0.2 * path.effects[0].heldout_before);
  EXPECT_DOUBLE_EQ(path.effects[0].share, 1.0);
}

TEST(NetworkPath, PeriodicSpikesAreNamedWithTheirPeriod) {
  LinkAnswers a = clean_link();
  for (std::size_t i = 0; i < kAnswers; ++i) {
    if (i % 512 < 3) a.round_trip[i] += 0.005;  // 5 ms for 3 answers every 0.5 s
  }
  const NetworkPath path = identify_network_path(a, declared_2ms(), kDt);
  ASSERT_EQ(names(path), std::set<std::string>{"periodic spikes"});
  EXPECT_NEAR(path.spike_period, 0.5, 2 * kDt);
  EXPECT_NEAR(path.spike_height, 0.005, 2e-4);
}

// On a loaded host the spikes' heights vary: here every seventh burst is the highest, so the
// highest spikes alone recur on a grid of 7 periods that holds six starts. The grid of the
// period itself, full with forty starts, must win (a coverage over 1 once let the coarse one).
TEST(NetworkPath, PeriodicSpikesWhoseHighestRecurOnACoarserGridKeepTheirOwnPeriod) {
  LinkAnswers a = clean_link();
  for (std::size_t i = 0; i < a.round_trip.size(); ++i) {
    const std::size_t burst = i / 256;
    if (i % 256 < 3) a.round_trip[i] += burst % 7 == 0 ? 0.008 : 0.006;  // every 0.25 s
  }
  const NetworkPath path = identify_network_path(a, declared_2ms(), kDt);
  ASSERT_EQ(names(path), std::set<std::string>{"periodic spikes"});
  EXPECT_NEAR(path.spike_period, 0.25, 2 * kDt);
}

TEST(NetworkPath, PeriodicSpikesAmongAFewStrayOnesAreStillNamedWithTheirPeriodAndPhase) {
  LinkAnswers a = clean_link();
  for (std::size_t i = 0; i < kAnswers; ++i) {
    if (i % 512 >= 100 && i % 512 < 103) a.round_trip[i] += 0.005;  // 5 ms, 3 answers, every 0.5 s
  }
  // A busy host's stray spikes, off the period, the first one before the periodic ones start.
  for (std::size_t i : {40u, 3000u, 7500u}) a.round_trip[i] += 0.004;
  const NetworkPath path = identify_network_path(a, declared_2ms(), kDt);
  ASSERT_EQ(names(path), std::set<std::string>{"periodic spikes"})
      << path.spikes << " spikes, period " << path.spike_period;
  EXPECT_NEAR(path.spike_period, 0.5, 2 * kDt);
  // The model's spikes sit on the periodic ones, not on the stray first spike.
  EXPECT_GT(path.model[612] - path.model[600], 0.004);
  EXPECT_LT(path.model[40] - path.model[600], 1e-4);
}

TEST(NetworkPath, ABurstOfLostAnswersIsNamedWithItsLength) {
  LinkAnswers a = clean_link();
  const auto cut = [&](auto& v) { v.erase(v.begin() + 5000, v.begin() + 5012); };
  cut(a.time);
  cut(a.answered_step);
  cut(a.round_trip);
  cut(a.injected);
  const NetworkPath path = identify_network_path(a, {0.002, 0.0, 0.001}, kDt);
  ASSERT_EQ(names(path), std::set<std::string>{"lost answers"});
  EXPECT_EQ(path.lost, 12u);
  EXPECT_EQ(path.longest_burst, 12u);
}

TEST(NetworkPath, LostAnswersWithinTheDeclaredLossAreNotNamed) {
  LinkAnswers a = clean_link();
  for (std::size_t k : {9000u, 7000u, 3000u}) {  // three single losses at 1 % declared
    for (auto* v : {&a.time, &a.round_trip, &a.injected})
      v->erase(v->begin() + static_cast<std::ptrdiff_t>(k));
    a.answered_step.erase(a.answered_step.begin() + static_cast<std::ptrdiff_t>(k));
  }
  const NetworkPath path = identify_network_path(a, {0.002, 0.0, 0.01}, kDt);
  EXPECT_EQ(path.lost, 3u);
  EXPECT_TRUE(path.effects.empty());
}

// Answers as a real-time record holds them: with the coordinator's answer count, and with the
// answers at `taken_out` not taken by the loop (superseded: `received` says whether they reached
// the coordinator, or were lost).
LinkAnswers counted_link(const std::vector<std::size_t>& taken_out, bool received) {
  LinkAnswers a = clean_link();
  for (std::size_t i = 0; i < kAnswers; ++i) a.answers.push_back(static_cast<std::int64_t>(i + 1));
  std::int64_t never = 0;
  std::vector<std::size_t> out = taken_out;
  std::sort(out.begin(), out.end());
  for (std::size_t i = 0, o = 0; i < kAnswers; ++i) {
    if (o < out.size() && out[o] == i) {
      ++o;
      never += received ? 0 : 1;
      continue;
    }
    a.answers[i] -= never;
  }
  for (auto it = out.rbegin(); it != out.rend(); ++it) {
    const auto at = static_cast<std::ptrdiff_t>(*it);
    for (auto* v : {&a.time, &a.round_trip, &a.injected}) v->erase(v->begin() + at);
    for (auto* v : {&a.answered_step, &a.answers}) v->erase(v->begin() + at);
  }
  return a;
}

TEST(NetworkPath, AnswersSupersededWithinAStepAreNotLost) {
  std::vector<std::size_t> superseded;
  for (std::size_t k = 100; k < kAnswers; k += 97) superseded.push_back(k);
  superseded.push_back(5001);  // two in a row
  superseded.push_back(5002);
  const NetworkPath path =
      identify_network_path(counted_link(superseded, true), declared_2ms(), kDt);
  EXPECT_EQ(path.lost, 0u);
  EXPECT_EQ(path.superseded, superseded.size());
  EXPECT_TRUE(names(path).empty()) << path.effects.front().name;
  // Without the count, the same gaps read as lost answers.
  LinkAnswers uncounted = counted_link(superseded, true);
  uncounted.answers.clear();
  const NetworkPath old = identify_network_path(uncounted, declared_2ms(), kDt);
  EXPECT_EQ(old.lost, superseded.size());
  EXPECT_EQ(names(old), std::set<std::string>{"lost answers"});
}

TEST(NetworkPath, ABurstOfLostAnswersAmongSupersededOnesIsNamedWithItsLength) {
  std::vector<std::size_t> lost;
  for (std::size_t k = 5000; k < 5012; ++k) lost.push_back(k);
  LinkAnswers a = counted_link(lost, false);
  const NetworkPath path = identify_network_path(a, declared_2ms(), kDt);
  EXPECT_EQ(names(path), std::set<std::string>{"lost answers"});
  EXPECT_EQ(path.lost, 12u);
  EXPECT_EQ(path.longest_burst, 12u);
  // Two of the twelve (at the gap's edge) reached the coordinator but were superseded: 10 lost,
  // in one burst.
  const auto after = std::find(a.answered_step.begin(), a.answered_step.end(), 5013);
  ASSERT_NE(after, a.answered_step.end());
  const auto i = static_cast<std::size_t>(after - a.answered_step.begin());
  for (std::size_t j = i; j < a.answers.size(); ++j) a.answers[j] += 2;
  const NetworkPath partly = identify_network_path(a, declared_2ms(), kDt);
  EXPECT_EQ(partly.lost, 10u);
  EXPECT_EQ(partly.superseded, 2u);
  EXPECT_EQ(partly.longest_burst, 10u);
}

TEST(NetworkPath, AnEffectTheConfigDeclaresIsNotNamed) {
  LinkAnswers a = clean_link();
  for (std::size_t i = 0; i < kAnswers; ++i) a.round_trip[i] += 0.003 * a.time[i] / 10.0;
  DeclaredLink declared = declared_2ms();
  declared.drift = true;
  EXPECT_TRUE(names(identify_network_path(a, declared, kDt)).empty());
}

// A loaded host's stray spikes: `count` answers delayed by 1 to 5 ms at random steps, a few of
// them by tens of ms.
void add_strays(LinkAnswers& a, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> at(0, kAnswers - 1);
  std::uniform_real_distribution<double> size(0.001, 0.005);
  for (int i = 0; i < count; ++i) a.round_trip[at(rng)] += i % 50 == 0 ? 0.040 : size(rng);
}

TEST(NetworkPath, PeriodicSpikesAreNamedAmongManyMoreStrayOnes) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    LinkAnswers a = clean_link(seed);
    for (std::size_t i = 0; i < kAnswers; ++i) a.round_trip[i] += i % 256 < 3 ? 0.006 : 0.0;
    add_strays(a, 800, seed);  // 40 bursts of spikes, 800 strays
    const NetworkPath path = identify_network_path(a, declared_2ms(), kDt);
    EXPECT_EQ(names(path), std::set<std::string>{"periodic spikes"}) << "seed " << seed;
    EXPECT_NEAR(path.spike_period, 0.25, 0.002) << "seed " << seed;
  }
}

TEST(NetworkPath, ManyStraySpikesAloneNameNothing) {
  for (std::uint64_t seed : {4u, 5u, 6u}) {
    LinkAnswers a = clean_link(seed);
    add_strays(a, 800, seed);
    EXPECT_TRUE(names(identify_network_path(a, declared_2ms(), kDt)).empty()) << "seed " << seed;
  }
}

TEST(NetworkPath, DriftAndSpikesTogetherAreBothNamedWithShares) {
  LinkAnswers a = clean_link();
  for (std::size_t i = 0; i < kAnswers; ++i) {
    a.round_trip[i] += 0.003 * a.time[i] / 10.0 + (i % 512 < 3 ? 0.008 : 0.0);
  }
  const NetworkPath path = identify_network_path(a, declared_2ms(), kDt);
  ASSERT_EQ(names(path), (std::set<std::string>{"drifting delay", "periodic spikes"}));
  double shares = 0.0;
  for (const auto& e : path.effects) shares += e.share;
  EXPECT_NEAR(shares, 1.0, 1e-12);
}

TEST(NetworkPath, ANodeInjectingOtherThanDeclaredIsNamed) {
  LinkAnswers a = clean_link();
  const NetworkPath path = identify_network_path(a, {0.001, 0.0, 0.0}, kDt);
  ASSERT_EQ(names(path), std::set<std::string>{"injection"});
  EXPECT_NEAR(path.injected_mean, 0.002, 1e-12);
}

TEST(NetworkPath, TooFewAnswersAreRefusedNamingTheNode) {
  LinkAnswers a = clean_link();
  for (auto* v : {&a.time, &a.round_trip, &a.injected}) v->resize(10);
  a.answered_step.resize(10);
  try {
    identify_network_path(a, declared_2ms(), kDt);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("node 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rths::identify
