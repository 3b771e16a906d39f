// Never silent (identify/run/residual_floor.h): on records of an independent closed-loop
// simulation (independent_record.h), a clean record reads "none" with each channel's floor
// stated and no event, a held reading, spikes and an offset's step on the load cell are located
// in time with their kind in the text and the JSON's `unexplained` list (a held reading's share of
// the re-run's error with it put back), a rattle on the load cell for a moment, which no stage and no description holds, is
// reported on the load cell above the floor, in its window and at its frequency, and a force
// residual that follows the motion on the specimen, with its line in a lab's words (a damping the
// model lacks as the damping it is).
#include "identify/run/residual_floor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "tests/identify/independent_record.h"

namespace rths::identify {
namespace {

RunIdentification identify_rig(const std::string& name, const test::RigTruth& rig) {
  RunIdentification run =
      identify_run_record(test::independent_record(name, rig, 15.0), IdentifyOptions{});
  for (const auto& f : run.floors)
    std::printf("%s: %s (%s) residual %.4f, floor %.4f (noise %.5f, band %.5f)%s\n", name.c_str(),
                f.part.c_str(), f.channel_word.c_str(), f.level, f.floor, f.noise, f.band_noise,
                f.above ? (":\n  " + f.text()).c_str() : "");
  for (const auto& f : run.floors)
    if (!f.events.empty()) std::printf("  %s\n", f.events_text().c_str());
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
    for (const auto& f : run.floors) {
      EXPECT_FALSE(f.above) << f.part << "\n" << text;
      EXPECT_TRUE(f.events.empty()) << f.part << "\n" << text;
    }
    EXPECT_TRUE(run_record_json(run)["unexplained"].empty()) << text;
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

const ChannelFloor& force_floor(const RunIdentification& run) {
  for (const auto& f : run.floors)
    if (f.channel == Channel::kForce) return f;
  throw std::runtime_error("no force channel identified");
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
  // Where the residual lies (the largest compressions) the specimen reads above the model fitted
  // over both sides: a line on the model's output with its sign.
  EXPECT_EQ(force->relation_as.rfind("as measured / model +", 0), 0u) << text;
}

// A viscous damper of 300 N s/m beside the specimen, identified with the damping left out of the
// candidates: the force's residual is a line on the displacement's rate, said as the damping it
// is, with the sign a lab reads it by.
TEST(ResidualFloorRecords, AForceInProportionToTheRateIsSaidAsADamping) {
  test::RigTruth rig;
  rig.specimen_damping = 300.0;
  IdentifyOptions options;
  options.selection.candidates = {Effect::kFirstOrder};
  const RunIdentification run =
      identify_run_record(test::independent_record("floor_damper", rig, 15.0), options);
  const std::string text = run_record_text(run);
  const ChannelFloor& force = force_floor(run);
  ASSERT_TRUE(force.above) << text;
  EXPECT_EQ(force.relation, "the rate of the displacement read") << text;
  EXPECT_EQ(force.relation_as.rfind("as a damping of ", 0), 0u) << text;
  const double damping =
      std::stod(force.relation_as.substr(std::string("as a damping of ").size()));
  EXPECT_NEAR(damping, 300.0, 60.0) << text;
}

std::vector<ResidualEvent> of_kind(const ChannelFloor& f, EventKind kind) {
  std::vector<ResidualEvent> out;
  for (const auto& e : f.events)
    if (e.kind == kind) out.push_back(e);
  std::sort(out.begin(), out.end(),
            [](const ResidualEvent& a, const ResidualEvent& b) { return a.start < b.start; });
  return out;
}

// The JSON's `unexplained` entry on `part` whose kinds hold `kind`, or null.
nlohmann::json entry_of(const RunIdentification& run, const std::string& part,
                        const std::string& kind) {
  const nlohmann::json report = run_record_json(run);
  for (const auto& e : report["unexplained"]) {
    const auto& kinds = e["kinds"];
    if (e["part"] == part && std::find(kinds.begin(), kinds.end(), kind) != kinds.end()) return e;
  }
  return nullptr;
}

// The load cell's reading frozen over 7.0-7.4 s: a held sample there, on the load cell.
TEST(ResidualFloorRecords, AHeldReadingIsLocatedInTime) {
  test::RigTruth rig;
  rig.hold_start = 7.0;
  rig.hold_end = 7.4;
  const RunIdentification run = identify_rig("floor_held", rig);
  const std::string text = run_record_text(run);
  const ChannelFloor& force = force_floor(run);
  const auto held = of_kind(force, EventKind::kHeldSample);
  ASSERT_EQ(held.size(), 1u) << text;
  EXPECT_NEAR(held[0].start, 7.0, 0.002) << text;
  EXPECT_NEAR(held[0].end, 7.4, 0.002) << text;
  EXPECT_EQ(force.events_part, "load cell 1");
  // Modelled in the re-run: the residual inside it put back removes most of what the re-run
  // leaves (the frozen force drove the frame).
  ASSERT_TRUE(force.events_share.has_value()) << text;
  EXPECT_GT(*force.events_share, 0.5) << text;
  EXPECT_NE(force.events_text().find("; the re-run with them put back: share "), std::string::npos);
  EXPECT_NE(text.find("  located in time on load cell 1 (force): "), std::string::npos) << text;
  const nlohmann::json entry = entry_of(run, "load cell 1", "held_sample");
  ASSERT_FALSE(entry.is_null()) << text;
  EXPECT_NEAR(entry["when"][0]["start_s"].get<double>(), 7.0, 0.002);
}

// 400 N spikes on single samples of the load cell at 3.2, 8.6 and 11.3 s: each found at its time.
TEST(ResidualFloorRecords, SpikesAreLocatedEachAtItsTime) {
  test::RigTruth rig;
  rig.spike_force = 400.0;
  rig.spike_times = {3.2, 8.6, 11.3};
  const RunIdentification run = identify_rig("floor_spikes", rig);
  const std::string text = run_record_text(run);
  const auto spikes = of_kind(force_floor(run), EventKind::kSpike);
  ASSERT_EQ(spikes.size(), 3u) << text;
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(spikes[i].start, rig.spike_times[i], 0.002);
  EXPECT_FALSE(entry_of(run, "load cell 1", "spike").is_null()) << text;
}

// The rattle above is a burst in its seconds too.
TEST(ResidualFloorRecords, ARattleIsABurstInItsSeconds) {
  test::RigTruth rig;
  rig.rattle_force = 300.0;
  rig.rattle_frequency = 25.0;
  rig.rattle_start = 6.0;
  rig.rattle_end = 8.0;
  const RunIdentification run = identify_rig("floor_burst", rig);
  const std::string text = run_record_text(run);
  const auto bursts = of_kind(force_floor(run), EventKind::kBurst);
  ASSERT_EQ(bursts.size(), 1u) << text;
  EXPECT_NEAR(bursts[0].start, 6.0, 0.1) << text;
  EXPECT_NEAR(bursts[0].end, 8.0, 0.1) << text;
}

}  // namespace
}  // namespace rths::identify
