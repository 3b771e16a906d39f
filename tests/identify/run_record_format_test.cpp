// A run's identification as `rths identify RECORD.rthsrec` prints it (run_record_format.h): the
// formatters print the identification's own figures, so an effect has one magnitude in the
// channel section, in the findings and in the JSON. Records of rths's own runs with an effect
// their config does not declare (tests/identify/undeclared_run.h).
#include <gtest/gtest.h>

#include <string>

#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "tests/identify/independent_record.h"
#include "tests/identify/undeclared_run.h"

namespace rths::identify {
namespace {

// The JSON's parameter `name` of `effect` among `effects` ([{effect, parameters}]), or NaN.
double json_parameter(const nlohmann::json& effects, const std::string& effect,
                      const std::string& name) {
  for (const auto& e : effects)
    if (e["effect"] == effect)
      for (const auto& p : e["parameters"])
        if (p["name"] == name) return p["value"].get<double>();
  return std::nan("");
}

// An extra first-order lag: its time constant, with the fit's standard error, in the channel
// section of the text and in the JSON: the 8 ms put in.
TEST(RunRecordFormat, AnEffectsParametersAreInTheTextAndTheJson) {
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("format_first_order",
                                "receive_delay { first_order { time_constant: 0.008 } }"),
      options);
  const std::string text = run_record_text(run);
  EXPECT_NE(text.find("first_order: time_constant = 8"), std::string::npos) << text;
  const nlohmann::json channel = run_record_json(run)["actuators"][0]["channels"][0];
  bool found = false;
  for (const auto& effect : channel["effects"]) {
    if (effect["effect"] != "first_order") continue;
    const auto& p = effect["parameters"][0];
    EXPECT_EQ(p["name"], "time_constant");
    EXPECT_EQ(p["unit"], "s");
    EXPECT_NEAR(p["value"].get<double>(), 0.008, 0.0008) << p;
    EXPECT_GE(p["std_error"].get<double>(), 0.0) << p;
    found = true;
  }
  EXPECT_TRUE(found) << channel;
}

// A load cell's offset drift: its offset and drift are one pair of numbers (the offset at t = 0
// of the run and the drift per second, as the sensor_drift stage holds them) in the force
// channel's section, in the findings and in the JSON's both places; the printed findings are the
// identification's own, not computed again.
TEST(RunRecordFormat, OneFindingHasOneMagnitudeInEverySectionAndInTheJson) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("format_load_cell",
                                "receive_delay { sensor_drift { force_offset: 500 } }"),
      IdentifyOptions{});
  const std::string text = run_record_text(run);
  const nlohmann::json json = run_record_json(run);
  const Finding* finding = nullptr;
  for (const auto& f : run.findings)
    if (f.part == "load cell 1" && f.effect == "offset_drift") finding = &f;
  ASSERT_NE(finding, nullptr) << text;
  ASSERT_EQ(finding->parameters.size(), 2u);
  const double offset = finding->parameters[0].value;
  EXPECT_NEAR(offset, 500.0, 25.0) << text;
  const EffectEstimate* estimate =
      run.actuators.at(0).estimate(Channel::kForce, Effect::kOffsetDrift);
  ASSERT_NE(estimate, nullptr);
  EXPECT_EQ(estimate->parameters[0].value, offset);
  // The text: the channel section's line and the findings' line carry the same description.
  const std::string described = finding->parameters[0].describe();
  const std::size_t first = text.find(described);
  ASSERT_NE(first, std::string::npos) << described << "\n" << text;
  EXPECT_NE(text.find(described, first + 1), std::string::npos) << described << "\n" << text;
  // The JSON: the channel's effect and the finding.
  for (const auto& channel : json["actuators"][0]["channels"])
    if (channel["channel"] == "force")
      EXPECT_EQ(json_parameter(channel["effects"], "offset_drift", "offset"), offset) << channel;
  bool in_findings = false;
  for (const auto& f : json["undeclared"])
    if (f["part"] == "load cell 1" && f["effect"] == "offset_drift") {
      EXPECT_EQ(f["parameters"][0]["value"].get<double>(), offset) << f;
      EXPECT_EQ(f["magnitude"], finding->magnitude);
      in_findings = true;
    }
  EXPECT_TRUE(in_findings) << json["undeclared"];
}

// A link's drift is not re-run (in lockstep its lag does not reach the response): its finding has
// no share (null, not a 0 beside the link section's figure), and the link section's own part of
// its held-out error is said to be a held-out share, in the text and in the JSON.
TEST(RunRecordFormat, AShareIsTheReRunsAndAHeldOutShareIsSaidToBeOne) {
  test::RigTruth rig;
  rig.network.drift = 0.005;
  rig.network.jitter = 40e-6;
  const RunIdentification run = identify_run_record(
      test::independent_record("format_link_drift", rig, 15.0), IdentifyOptions{});
  const std::string text = run_record_text(run);
  const nlohmann::json json = run_record_json(run);
  EXPECT_NE(text.find("held-out share"), std::string::npos) << text;
  EXPECT_EQ(text.find(", share "), std::string::npos) << text;
  ASSERT_FALSE(json["links"][0]["undeclared"].empty()) << json["links"];
  for (const auto& e : json["links"][0]["undeclared"]) {
    EXPECT_TRUE(e.contains("heldout_share")) << e;
    EXPECT_FALSE(e.contains("share")) << e;
  }
  bool found = false;
  for (const auto& f : json["undeclared"])
    if (f["part"] == "link to node 1") {
      EXPECT_TRUE(f["share"].is_null()) << f;
      EXPECT_FALSE(f["rerun"].get<bool>()) << f;
      found = true;
    }
  EXPECT_TRUE(found) << json["undeclared"];
}

}  // namespace
}  // namespace rths::identify
