// The description of what an identified model leaves (identify/run/unexplained.h): each test on
// residuals made to hold one signature, then records of an independent closed-loop simulation
// (independent_record.h) whose rig has an effect identify has no stage for: each is located on
// its part and channel with the right kind and a plausible share, no effect is named in its place
// with a magnitude, and a clean record reports nothing unexplained.
#include "identify/run/unexplained.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "tests/identify/independent_record.h"

namespace rths::identify {
namespace {

constexpr double kDt = 0.001;
constexpr std::size_t kSamples = 15000;

struct Synthetic {
  std::vector<double> time, prediction, residual;
};

// A model's output like a storey's drift under a ground motion (mm, several frequencies and an
// envelope), and Gaussian noise of `noise` as the residual.
Synthetic synthetic(double noise, std::uint64_t seed = 3) {
  Synthetic out;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t j = 0; j < kSamples; ++j) {
    const double t = static_cast<double>(j) * kDt, w = 2.0 * std::numbers::pi;
    const double envelope = 0.5 + 0.5 * std::sin(w * 0.05 * t);
    out.time.push_back(t);
    out.prediction.push_back(envelope *
                             (8.0 * std::sin(w * 1.9 * t) + 3.0 * std::sin(w * 0.7 * t + 1.0) +
                              1.5 * std::sin(w * 3.3 * t + 2.0)));
    out.residual.push_back(noise * normal(rng));
  }
  return out;
}

ResidualDescription described(const Synthetic& s) {
  return describe_residual(s.time, s.residual, s.prediction, kDt);
}

TEST(DescribeResidual, NoiseAloneIsNotDescribed) {
  for (std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const ResidualDescription d = described(synthetic(0.05, seed));
    EXPECT_FALSE(d.any()) << "seed " << seed << ": " << d.kinds().size() << " kinds";
  }
}

TEST(DescribeResidual, ASinusoidIsPeriodicWithItsFrequencyAndAmplitude) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += 0.3 * std::sin(2.0 * std::numbers::pi * 7.0 * s.time[j] + 0.4);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.periodic.has_value());
  EXPECT_NEAR(d.periodic->frequency, 7.0, 0.01);
  EXPECT_NEAR(d.periodic->amplitude, 0.3, 0.015);
  EXPECT_FALSE(d.amplitude || d.direction || d.time_varying);
  EXPECT_GT(d.explained, 0.9);
}

// Stiffer on one side than on the other: a residual even in the input.
TEST(DescribeResidual, AResidualOfTheInputsSignIsDirectionWithItsAsymmetry) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j) s.residual[j] += 0.1 * std::abs(s.prediction[j]);
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.direction.has_value());
  EXPECT_NEAR(d.direction->asymmetry_pct, 20.0, 2.0);  // +10 % on one side, -10 % on the other
  EXPECT_FALSE(d.periodic || d.amplitude);
}

TEST(DescribeResidual, AReadingThatFallsShortAtLargeInputsIsAmplitude) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] -= 0.002 * s.prediction[j] * s.prediction[j] * s.prediction[j];
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.amplitude.has_value());
  EXPECT_LT(d.amplitude->ratio_change_pct, -5.0);
  EXPECT_FALSE(d.periodic || d.direction);
}

TEST(DescribeResidual, LoadingAndUnloadingApartIsDirectionWithItsWidth) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 1; j < kSamples; ++j)
    s.residual[j] += s.prediction[j] >= s.prediction[j - 1] ? 0.2 : -0.2;
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.direction.has_value());
  EXPECT_NEAR(d.direction->hysteresis_width, 0.4, 0.05);
}

TEST(DescribeResidual, AGainThatFallsOverTheRecordIsTimeVaryingWithItsChange) {
  Synthetic s = synthetic(0.05);
  for (std::size_t j = 0; j < kSamples; ++j)
    s.residual[j] += -0.2 * (s.time[j] / s.time.back() - 0.5) * s.prediction[j];
  const ResidualDescription d = described(s);
  ASSERT_TRUE(d.time_varying.has_value());
  EXPECT_NEAR(d.time_varying->change_pct, -20.0, 2.0);
  EXPECT_FALSE(d.periodic || d.amplitude || d.direction);
}

// --- records of an independent simulation ---

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
  bool named = false;
  for (const auto& f : run.findings)
    named = named || (f.part == "specimen 1" && f.effect == "time_varying_stiffness" &&
                      !f.parameters.empty());
  EXPECT_TRUE(named) << run_record_text(run);
  EXPECT_EQ(on(run, "specimen 1"), nullptr) << run_record_text(run);
  EXPECT_EQ(on(run, "load cell 1"), nullptr) << run_record_text(run);
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
    for (const auto& a : run.actuators)
      EXPECT_TRUE(a.not_named.empty()) << name << "\n" << run_record_text(run);
  }
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
