// The description of what an identified model leaves (identify/run/unexplained.h), on records of
// an independent closed-loop simulation (independent_record.h) whose rig has an effect identify
// has no stage for: each is located on its part and channel with the right kind and a plausible
// share, no effect is named in its place with a magnitude (an offset that steps once is no
// drift), and a clean record reports nothing unexplained. The description's numerics on made residuals: description_test.cpp.
#include "identify/run/unexplained.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
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
  std::printf("%s", run_record_text(run).c_str());
  if (run.residual)
    std::printf("%s: worst floor NRMSE declared %.4f -> identified %.4f\n", name.c_str(),
                run.residual->declared, run.residual->identified);
  for (const auto& d : run.residual ? run.residual->described : std::vector<ResidualShare>{})
    std::printf("%s: %s (%s) described put back: identified %.4f -> %.4f\n", name.c_str(),
                d.link.c_str(), d.effect.c_str(), run.residual->identified,
                run.residual->identified - d.removed);
  return run;
}

const Unexplained* on(const RunIdentification& run, const std::string& part) {
  for (const auto& u : run.unexplained)
    if (u.part == part) return &u;
  return nullptr;
}

constexpr double kSpecimenStiffness = 52638.0;  // N/m, independent_record.h's k_e

const Finding* moving_on(const RunIdentification& run, const std::string& part,
                         const std::string& effect) {
  for (const auto& f : run.findings)
    if (f.part == part && f.effect == effect) return &f;
  return nullptr;
}

bool has_kind(const Unexplained& u, const std::string& kind) {
  for (const auto& k : u.description.kinds())
    if (k == kind) return true;
  return false;
}

// No finding on the rig's parts: what has no stage is not forced into a name.
void expect_nothing_named(const RunIdentification& run) {
  for (const auto& f : run.findings)
    ADD_FAILURE() << "named " << f.part << ": " << f.effect << ": " << f.magnitude;
}

// Sensor noise and 16-bit converters only, over several draws of the noise.
TEST(UnexplainedRecords, ACleanRecordLeavesNothingUnexplained) {
  for (std::uint64_t seed : {7u, 11u, 23u, 42u}) {
    test::RigTruth rig;
    rig.seed = seed;
    const RunIdentification run = identify_rig("unexplained_clean", rig);
    EXPECT_TRUE(run.unexplained.empty()) << "seed " << seed << "\n" << run_record_text(run);
    EXPECT_NE(run_record_text(run).find("unexplained, every part and channel: none"),
              std::string::npos);
    EXPECT_EQ(run_record_json(run)["unexplained"], nlohmann::json::array());
    for (const auto& a : run.actuators) EXPECT_TRUE(a.not_named.empty()) << "seed " << seed;
  }
}

// A pump's 100 N ripple at 7 Hz on the specimen's force, identified once for the tests that read
// it.
const RunIdentification& ripple_run() {
  static const RunIdentification run = [] {
    test::RigTruth rig;
    rig.force_ripple = 100.0;
    rig.ripple_frequency = 7.0;
    return identify_rig("ripple", rig);
  }();
  return run;
}

TEST(UnexplainedRecords, APumpsRippleIsPeriodicOnTheLoadCell) {
  const RunIdentification& run = ripple_run();
  const Unexplained* u = on(run, "load cell 1");
  ASSERT_NE(u, nullptr) << run_record_text(run);
  EXPECT_EQ(u->channel_word, "force");
  ASSERT_TRUE(u->description.periodic.has_value()) << run_record_text(run);
  EXPECT_NEAR(u->description.periodic->frequency, 7.0, 0.02);
  EXPECT_NEAR(u->description.periodic->amplitude, 100.0, 10.0);
  ASSERT_TRUE(u->share.has_value());
  EXPECT_GT(*u->share, 0.5) << run_record_text(run);
  expect_nothing_named(run);
}

TEST(UnexplainedRecords, ASpecimenStifferInCompressionIsDirectionOnTheSpecimen) {
  test::RigTruth rig;
  rig.compression_stiffness = 1.4;
  const RunIdentification run = identify_rig("compression", rig);
  const Unexplained* u = on(run, "specimen 1");
  ASSERT_NE(u, nullptr) << run_record_text(run);
  EXPECT_EQ(u->channel_word, "force");
  ASSERT_TRUE(has_kind(*u, "direction")) << run_record_text(run);
  // Tension reads 1 / 1.4 of compression: the positive side 25 to 45 % below the negative.
  EXPECT_LT(u->description.direction->asymmetry_pct, -25.0) << run_record_text(run);
  EXPECT_GT(u->description.direction->asymmetry_pct, -45.0) << run_record_text(run);
  ASSERT_TRUE(u->share.has_value());
  EXPECT_GT(*u->share, 0.5) << run_record_text(run);
  expect_nothing_named(run);
}

TEST(UnexplainedRecords, AnActuatorShortAtLargeStrokesIsAmplitudeOnTheActuator) {
  test::RigTruth rig;
  rig.actuator_cubic = 500.0;  // 10 % short at 14 mm
  const RunIdentification run = identify_rig("actuator_cubic", rig);
  const Unexplained* u = on(run, "actuator 1");
  ASSERT_NE(u, nullptr) << run_record_text(run);
  EXPECT_EQ(u->channel_word, "displacement");
  ASSERT_TRUE(has_kind(*u, "amplitude")) << run_record_text(run);
  EXPECT_LT(u->description.amplitude->ratio_change_pct, -2.0) << run_record_text(run);
  ASSERT_TRUE(u->share.has_value());
  EXPECT_GT(*u->share, 0.3) << run_record_text(run);
  expect_nothing_named(run);
}

// A stiffness that falls by 30 % over the run is the library's time_varying_stiffness: its fit
// beats the description (judge_named), so it is named with its magnitude and not described again
// as unexplained on the specimen.
TEST(UnexplainedRecords, ASofteningSpecimenIsTheLibrarysAndNotDescribedTwice) {
  test::RigTruth rig;
  rig.softening = 0.3;
  const RunIdentification run = identify_rig("softening", rig);
  const Finding* named = moving_on(run, "specimen 1", "time_varying_stiffness");
  ASSERT_NE(named, nullptr) << run_record_text(run);
  EXPECT_FALSE(named->parameters.empty());
  // Moving, not one constant: 52.6 kN/m falling steadily to 70 % of it over the 15 s.
  ASSERT_TRUE(named->moving.has_value()) << run_record_text(run);
  EXPECT_EQ(named->moving->shape, DriftShape::kLinear) << named->magnitude;
  EXPECT_NEAR(named->moving->start, kSpecimenStiffness * (1.0 - 0.3 * 0.375 / 15.0), 2000.0)
      << named->magnitude;
  EXPECT_NEAR(named->moving->end, kSpecimenStiffness * (1.0 - 0.3 * 14.625 / 15.0), 2000.0)
      << named->magnitude;
  EXPECT_NE(run_record_text(run).find(named->magnitude), std::string::npos);
  EXPECT_EQ(on(run, "specimen 1"), nullptr) << run_record_text(run);
  EXPECT_EQ(on(run, "load cell 1"), nullptr) << run_record_text(run);
}

// A specimen that loses 30 % of its stiffness at 9 s of the 15 s run (a capacity drop): a step
// there, from the declared stiffness to 70 % of it, whether the library's moving stiffness holds
// it or the description does.
TEST(UnexplainedRecords, ACapacityDropIsAStepAtItsTime) {
  test::RigTruth rig;
  rig.capacity_drop = 0.3;
  rig.drop_time = 9.0;
  const RunIdentification run = identify_rig("capacity_drop", rig);
  const std::string text = run_record_text(run);
  bool located = false;  // and located in time from 9 s on (events.h)
  for (const auto& f : run.floors)
    for (const auto& e : f.events)
      located = located || (e.kind == EventKind::kCapacityDrop && std::abs(e.start - 9.0) < 0.2);
  EXPECT_TRUE(located) << text;
  if (const Finding* named = moving_on(run, "specimen 1", "time_varying_stiffness")) {
    ASSERT_TRUE(named->moving.has_value()) << text;
    EXPECT_EQ(named->moving->shape, DriftShape::kStep) << text;
    EXPECT_NEAR(named->moving->at, 9.0, 0.75) << text;
    EXPECT_NEAR(named->moving->end / named->moving->start, 0.7, 0.05) << text;
    return;
  }
  const Unexplained* u = on(run, "specimen 1");
  ASSERT_NE(u, nullptr) << text;
  ASSERT_TRUE(u->description.time_varying.has_value()) << text;
  const ShapeFit& shape = u->description.time_varying->shape;
  EXPECT_EQ(shape.shape, DriftShape::kStep) << text;
  EXPECT_NEAR(shape.at, 9.0, 0.75) << text;
  EXPECT_NEAR(shape.end - shape.start, -0.3, 0.05) << text;
  EXPECT_NE(text.find("(a capacity drop)"), std::string::npos) << text;
}

// Where a stage of the library holds what the rig did, its fit beats the description: the effect
// is named and nothing is left unexplained (nor taken out of the names).
TEST(UnexplainedRecords, WhatTheLibraryHoldsIsNamedAndLeavesNothingUnexplained) {
  std::vector<std::pair<std::string, test::RigTruth>> rigs(6);
  rigs[0].first = "lib_velocity_limit";
  rigs[0].second.max_velocity = 0.05;
  rigs[1].first = "lib_backlash";
  rigs[1].second.backlash = 0.002;
  rigs[2].first = "lib_gain";
  rigs[2].second.gain = 1.15;
  rigs[3].first = "lib_bouc_wen";
  rigs[3].second.bouc_wen = true;
  rigs[4].first = "lib_damping";
  rigs[4].second.specimen_damping = 2000.0;
  rigs[5].first = "lib_load_cell";
  rigs[5].second.force_offset = 400.0;
  rigs[5].second.force_drift = 20.0;
  for (const auto& [name, rig] : rigs) {
    const RunIdentification run = identify_rig(name, rig);
    EXPECT_FALSE(run.findings.empty()) << name;
    EXPECT_TRUE(run.unexplained.empty()) << name << "\n" << run_record_text(run);
    for (const auto& a : run.actuators) {
      EXPECT_TRUE(a.not_named.empty()) << name << "\n" << run_record_text(run);
      EXPECT_TRUE(a.held_not_named.empty()) << name << "\n" << run_record_text(run);
    }
  }
}

// A damper whose force is 4000 N s^2/m^2 v |v| (v the specimen's drift rate, m/s) holds a
// damping coefficient several times larger over the larger half of its term than over the
// smaller: damping's form is not what the record shows, so it is not named; the re-run holds the
// fitted damping as the nearest form it has (at most half the declared model's error), and the
// report says so in the actuator's section and in the JSON.
TEST(UnexplainedRecords, ADamperInVTimesItsSizeIsHeldNotNamedAsDamping) {
  test::RigTruth rig;
  rig.squared_damping = 4000.0;
  const RunIdentification run = identify_rig("velocity_squared", rig);
  const std::string text = run_record_text(run);
  for (const Finding& f : run.findings) EXPECT_NE(f.effect, "damping") << text;
  const auto& held = run.actuators.at(0).held_not_named;
  ASSERT_EQ(held.size(), 1u) << text;
  EXPECT_EQ(held[0].effect, "damping");
  EXPECT_EQ(held[0].channel, Channel::kForce);
  EXPECT_NE(text.find("held, not named (force): damping not named: its form is not what the "
                      "record shows"),
            std::string::npos)
      << text;
  ASSERT_TRUE(run.residual.has_value());
  EXPECT_LT(run.residual->identified, 0.5 * run.residual->declared) << text;
  EXPECT_EQ(run_record_json(run)["actuators"][0]["held_not_named"].size(), 1u);
}

// The load cell's zero jumps by 60 N at 9 s and stays (a slip, a zero shift): one step, which a
// drift would only smear over the record, so no offset drift is named; the events search locates
// the step at its time (residual_floor.h).
TEST(UnexplainedRecords, AnOffsetThatStepsOnceIsNoDrift) {
  test::RigTruth rig;
  rig.step_force = 60.0;
  rig.step_time = 9.0;
  const RunIdentification run = identify_rig("offset_step", rig);
  const std::string text = run_record_text(run);
  EXPECT_EQ(moving_on(run, "load cell 1", "offset_drift"), nullptr) << text;
  bool located = false;
  for (const auto& f : run.floors)
    for (const auto& e : f.events)
      located |= f.channel == Channel::kForce && e.kind == EventKind::kStepChange &&
                 std::abs(e.start - 9.0) < 0.1;
  EXPECT_TRUE(located) << text;
}

// The text's line and the JSON's entry are one finding with one magnitude.
TEST(UnexplainedRecords, TheTextAndTheJsonGiveOneMagnitude) {
  const RunIdentification& run = ripple_run();
  const std::string text = run_record_text(run);
  const nlohmann::json json = run_record_json(run);
  ASSERT_EQ(json["unexplained"].size(), run.unexplained.size());
  ASSERT_FALSE(run.unexplained.empty()) << text;
  for (const auto& entry : json["unexplained"]) {
    const std::string line = entry["text"];
    EXPECT_NE(text.find("  " + line + "\n"), std::string::npos) << line << "\n" << text;
    std::ostringstream share;
    share << "; share " << std::llround(entry["share_pct"].get<double>()) << " %";
    EXPECT_NE(line.find(share.str()), std::string::npos) << line;
    if (entry["periodic"].is_null()) continue;
    std::ostringstream frequency, amplitude;
    frequency.setf(std::ios::fixed);
    frequency.precision(2);
    frequency << "periodic at " << entry["periodic"]["frequency_hz"].get<double>() << " Hz, ";
    amplitude.precision(3);
    amplitude << entry["periodic"]["amplitude"].get<double>() << " N";
    EXPECT_NE(line.find(frequency.str() + amplitude.str()), std::string::npos) << line;
  }
}

}  // namespace
}  // namespace rths::identify
