// Never silent (identify/run/residual_floor.h): a residual concentrated in time is located in its
// windows and noise is spread over the record; on records of an independent closed-loop
// simulation (independent_record.h), a clean record reads "none" with each channel's floor
// stated, a rattle on the load cell for a moment, which no stage and no description holds, is
// reported on the load cell above the floor, in its window and at its frequency, and a force
// residual that follows the motion on the specimen.
#include "identify/run/residual_floor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "tests/identify/independent_record.h"

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

TEST(ResidualFloor, NoiseAloneIsSpreadOverTheRecord) {
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const Series s = noise(0.05, seed);
    EXPECT_TRUE(residual_windows(s.time, s.residual).empty()) << "seed " << seed;
  }
}

// A 5 Hz burst over 6-9 s (windows 8 to 11) on noise: one window span, 6-9 s, holding most of
// the power; a second, weaker burst at 12.0-12.75 s comes second.
TEST(ResidualFloor, BurstsAreLocatedInTheirWindowsLargestFirst) {
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

RunIdentification identify_rig(const std::string& name, const test::RigTruth& rig) {
  RunIdentification run =
      identify_run_record(test::independent_record(name, rig, 15.0), IdentifyOptions{});
  for (const auto& f : run.floors)
    std::printf("%s: %s (%s) residual %.4f, floor %.4f (noise %.5f, band %.5f)%s\n", name.c_str(),
                f.part.c_str(), f.channel_word.c_str(), f.level, f.floor, f.noise, f.band_noise,
                f.above ? (":\n  " + f.text()).c_str() : "");
  return run;
}

// Sensor noise and 16-bit converters only: every channel at its floor, and the report says
// "none" stating each channel's floor.
TEST(ResidualFloorRecords, ACleanRecordIsAtItsFloorAndSaysSo) {
  for (std::uint64_t seed : {7u, 23u}) {
    test::RigTruth rig;
    rig.seed = seed;
    const RunIdentification run = identify_rig("floor_clean", rig);
    const std::string text = run_record_text(run);
    const std::size_t line = text.find("unexplained, every part and channel:");
    std::printf("%s", text.substr(line, text.find('\n', line) + 1 - line).c_str());
    ASSERT_EQ(run.floors.size(), 2u) << text;
    for (const auto& f : run.floors) EXPECT_FALSE(f.above) << f.part << "\n" << text;
    EXPECT_NE(text.find("unexplained, every part and channel: none (every channel at its floor"),
              std::string::npos)
        << text;
    EXPECT_NE(text.find("specimen 1 (force) "), std::string::npos) << text;
  }
}

// A 300 N rattle at 25 Hz on the load cell over 6-8 s of a 15 s record: the force channel is
// above its floor, and the report locates it there, at that frequency.
TEST(ResidualFloorRecords, ARattleForAMomentIsLocatedInTimeAndFrequency) {
  test::RigTruth rig;
  rig.rattle_force = 300.0;
  rig.rattle_frequency = 25.0;
  rig.rattle_start = 6.0;
  rig.rattle_end = 8.0;
  const RunIdentification run = identify_rig("floor_rattle", rig);
  const std::string text = run_record_text(run);
  const ChannelFloor* force = nullptr;
  for (const auto& f : run.floors)
    if (f.channel == Channel::kForce) force = &f;
  ASSERT_NE(force, nullptr) << text;
  ASSERT_TRUE(force->above) << text;
  EXPECT_EQ(force->part, "load cell 1") << text;  // it follows no motion: the reading's
  ASSERT_FALSE(force->windows.empty()) << text;
  EXPECT_GE(force->windows[0].start, 6.0 - 0.75) << text;
  EXPECT_LE(force->windows[0].end, 8.0 + 0.75) << text;
  EXPECT_GT(force->windows[0].share, 0.6) << text;
  EXPECT_NEAR(force->peak_hz, 25.0, 0.5) << text;
  EXPECT_NE(text.find("  " + force->text() + "\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("unexplained, every part and channel: none"), std::string::npos) << text;
  EXPECT_TRUE(run_record_json(run)["residual_floor"][1]["above"].get<bool>()) << text;
}

// A specimen 1.4 x stiffer in compression: its force channel is above its floor, and a function
// of the motion explains its residual (which the fitted stiffness left uncorrelated with the
// displacement), so it is the specimen's, not its load cell's.
TEST(ResidualFloorRecords, AForceThatFollowsTheMotionIsTheSpecimens) {
  test::RigTruth rig;
  rig.compression_stiffness = 1.4;
  const RunIdentification run = identify_rig("floor_compression", rig);
  const std::string text = run_record_text(run);
  const ChannelFloor* force = nullptr;
  for (const auto& f : run.floors)
    if (f.channel == Channel::kForce) force = &f;
  ASSERT_NE(force, nullptr) << text;
  ASSERT_TRUE(force->above) << text;
  EXPECT_EQ(force->part, "specimen 1") << text;
  EXPECT_FALSE(force->relation.empty()) << text;
  EXPECT_GE(force->explained, 0.5) << text;
}

}  // namespace
}  // namespace rths::identify
