// The declared model as a config file: reading, every refusal naming file and field, the
// physical bounds at a record's scales, the declarations honoured by the fit, and the round trip
// of an identified model through the file.
#include "identify/model/declared_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <google/protobuf/text_format.h>

#include <cmath>

#include "identify/fit/selection.h"
#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::string error_of(const std::string& text) {
  try {
    parse_declared_model(text, "lab.textproto");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

const ParamDeclaration& declaration(const DeclaredChannel& channel, const std::string& name) {
  for (const auto& d : channel.parameters) {
    if (d.name == name) return d;
  }
  throw std::out_of_range(name);
}

TEST(DeclaredModelTest, ReadsStagesKindEffectsAndEveryParameterField) {
  const DeclaredModel m = parse_declared_model(R"(
    actuator {
      stages: "delay"
      stages: "first_order"
      parameters { name: "delay" initial: 0.015 min: 0.001 max: 0.05 }
      parameters { name: "gain" initial: 1 fixed: true }
    }
    specimen {
      kind: "mr_damper"
      effects: "offset_drift"
      parameters { name: "stiffness" max: 1e6 }
    })",
                                               "lab.textproto");
  ASSERT_TRUE(m.actuator && m.specimen);
  EXPECT_EQ(m.actuator->effects, (std::vector<Effect>{Effect::kDelay, Effect::kFirstOrder}));
  const auto& delay = declaration(*m.actuator, "delay");
  EXPECT_DOUBLE_EQ(*delay.initial, 0.015);
  EXPECT_DOUBLE_EQ(*delay.lower, 0.001);
  EXPECT_DOUBLE_EQ(*delay.upper, 0.05);
  EXPECT_FALSE(delay.fixed);
  EXPECT_TRUE(declaration(*m.actuator, "gain").fixed);
  EXPECT_EQ(m.specimen->kind, SpecimenKind::kMrDamper);
  auto expected = kind_effects(SpecimenKind::kMrDamper);
  expected.push_back(Effect::kOffsetDrift);
  EXPECT_EQ(m.specimen->effects, expected);
  const auto& k = declaration(*m.specimen, "stiffness");
  EXPECT_FALSE(k.lower.has_value());
  EXPECT_DOUBLE_EQ(*k.upper, 1e6);
}

TEST(DeclaredModelTest, AnAbsentChannelIsLeftToTheFlags) {
  const DeclaredModel m = parse_declared_model("specimen { kind: \"linear_spring\" }", "f");
  EXPECT_FALSE(m.actuator.has_value());
  ASSERT_TRUE(m.specimen.has_value());
  EXPECT_EQ(m.specimen->effects, std::vector<Effect>{Effect::kStiffness});
}

TEST(DeclaredModelTest, BadInputIsRefusedNamingFileAndField) {
  EXPECT_THAT(error_of("actuator { stages: \"delay\" parameters { name: \"tau\" initial: 0.01 } }"),
              AllOf(HasSubstr("lab.textproto: actuator.parameters[0] (tau)"),
                    HasSubstr("unknown parameter 'tau'"), HasSubstr("gain, delay")));
  EXPECT_THAT(
      error_of("actuator { stages: \"delay\" parameters { name: \"delay\" min: 0.05 max: 0.01 } }"),
      AllOf(HasSubstr("lab.textproto: actuator.parameters[0] (delay)"),
            HasSubstr("min 0.05 > max 0.01")));
  EXPECT_THAT(error_of("specimen { kind: \"linear_spring\" "
                       "parameters { name: \"stiffness\" initial: 5 min: 10 } }"),
              AllOf(HasSubstr("specimen.parameters[0] (stiffness)"),
                    HasSubstr("initial 5 is below min 10")));
  EXPECT_THAT(error_of("specimen { kind: \"linear_spring\" "
                       "parameters { name: \"stiffness\" initial: 50 max: 10 } }"),
              HasSubstr("initial 50 is above max 10"));
  EXPECT_THAT(
      error_of("actuator { parameters { name: \"gain\" fixed: true } }"),
      AllOf(HasSubstr("actuator.parameters[0] (gain)"), HasSubstr("fixed needs an initial value")));
  EXPECT_THAT(
      error_of("actuator { stages: \"dealy\" }"),
      AllOf(HasSubstr("lab.textproto: actuator.stages[0]"), HasSubstr("unknown effect 'dealy'")));
  EXPECT_THAT(error_of("actuator { stages: \"stiffness\" }"),
              HasSubstr("does not apply to channel 'measured'"));
  EXPECT_THAT(error_of("actuator { stages: \"delay\" stages: \"delay\" }"),
              AllOf(HasSubstr("actuator.stages[1]"), HasSubstr("declared twice")));
  EXPECT_THAT(error_of("specimen { kind: \"spring\" }"),
              AllOf(HasSubstr("specimen.kind"), HasSubstr("unknown specimen kind 'spring'")));
  EXPECT_THAT(
      error_of("specimen { kind: \"bouc_wen\" effects: \"stiffness\" }"),
      AllOf(HasSubstr("specimen.effects[0]"), HasSubstr("already part of kind 'bouc_wen'")));
  EXPECT_THAT(error_of("actuator { stages: \"delay\" parameters { name: \"delay\" } "
                       "parameters { name: \"delay\" } }"),
              AllOf(HasSubstr("actuator.parameters[1] (delay)"), HasSubstr("declared twice")));
  // Syntax and unknown fields: the text-format reader's line and column.
  EXPECT_THAT(error_of("actuator {\n  stage: \"delay\"\n}"),
              AllOf(HasSubstr("lab.textproto:2:"), HasSubstr("stage")));
}

TEST(DeclaredModelTest, ValuesBeyondThePhysicalBoundsAreRefusedForTheRecord) {
  SignalScales scales;
  scales.duration = 10.0;
  scales.dt = 0.001;
  const DeclaredModel spring = parse_declared_model(
      "specimen { kind: \"linear_spring\" parameters { name: \"stiffness\" min: -5 } }",
      "lab.textproto");
  try {
    check_physical_bounds(*spring.specimen, Channel::kForce, scales, spring.source);
    FAIL() << "a negative stiffness was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("lab.textproto: specimen.parameters[0] (stiffness)"),
                                HasSubstr("min -5 N/m is below the physical bound 0"),
                                HasSubstr("a negative stiffness")));
  }
  const DeclaredModel late = parse_declared_model(
      "actuator { stages: \"delay\" parameters { name: \"delay\" max: 7 } }", "lab.textproto");
  try {
    check_physical_bounds(*late.actuator, Channel::kMeasured, scales, late.source);
    FAIL() << "a delay longer than the record allows was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("actuator.parameters[0] (delay)"),
                                HasSubstr("above the physical bound 1 s")));
  }
  const DeclaredModel fine = parse_declared_model(
      "actuator { stages: \"delay\" parameters { name: \"delay\" min: 0 max: 0.05 } }", "f");
  EXPECT_NO_THROW(check_physical_bounds(*fine.actuator, Channel::kMeasured, scales, fine.source));
}

class DeclaredFitTest : public ::testing::Test {
 protected:
  void SetUp() override {
    GeneratorSpec spec;
    spec.duration = 12.0;
    spec.delay = 0.012;
    signals_ = make_signals(generate_measured(spec), Channel::kMeasured);
    split_ = holdout_split(signals_.size(), 0.3, HoldoutMode::kBlocks, 10);
  }
  ChannelSignals signals_;
  Split split_;
};

TEST_F(DeclaredFitTest, AFixedParameterIsHeldAndBoundsAreKept) {
  const DeclaredModel m = parse_declared_model(
      "actuator { stages: \"delay\" "
      "parameters { name: \"delay\" initial: 0.004 fixed: true } }",
      "f");
  const ChannelModel held =
      fit_declared(signals_, split_, m.actuator->effects, {}, m.actuator->parameters);
  EXPECT_DOUBLE_EQ(*held.param(Effect::kDelay, "delay", signal_scales(signals_)), 0.004);
  // Free, the same data give the generator's 12 ms: the hold above is the declaration's doing.
  const ChannelModel free = fit_declared(signals_, split_, m.actuator->effects, {});
  EXPECT_NEAR(*free.param(Effect::kDelay, "delay", signal_scales(signals_)), 0.012, 5e-4);

  const DeclaredModel bounded = parse_declared_model(
      "actuator { stages: \"delay\" parameters { name: \"delay\" min: 0 max: 0.008 } }", "f");
  const FitResult fit = fit_channel(
      fit_declared(signals_, split_, bounded.actuator->effects, {}, bounded.actuator->parameters),
      signals_, split_);
  EXPECT_NEAR(*fit.model.param(Effect::kDelay, "delay", signal_scales(signals_)), 0.008, 1e-9);
  ASSERT_EQ(fit.bound_hits.size(), 1u);
  EXPECT_EQ(fit.bound_hits[0].message(), "the data want delay above 0.008");
}

TEST_F(DeclaredFitTest, TheIdentifiedModelReadsBackAsTheSameModel) {
  const DeclaredModel m = parse_declared_model(
      "actuator { stages: \"delay\" stages: \"first_order\" "
      "parameters { name: \"delay\" min: 0.002 max: 0.05 } }",
      "f");
  const FitResult fit =
      fit_channel(fit_declared(signals_, split_, m.actuator->effects, {}, m.actuator->parameters),
                  signals_, split_);
  std::string text;
  ASSERT_TRUE(google::protobuf::TextFormat::PrintToString(to_config(&fit.model, nullptr), &text));
  const DeclaredModel back = parse_declared_model(text, "written");
  ASSERT_TRUE(back.actuator.has_value());
  EXPECT_FALSE(back.specimen.has_value());
  EXPECT_EQ(back.actuator->effects, fit.model.effects);
  const auto specs = fit.model.specs(signal_scales(signals_));
  ASSERT_EQ(back.actuator->parameters.size(), specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const auto& d = declaration(*back.actuator, specs[i].name);
    EXPECT_EQ(*d.initial, fit.model.params[i]) << specs[i].name;  // bit for bit
  }
  EXPECT_DOUBLE_EQ(*declaration(*back.actuator, "delay").lower, 0.002);
  EXPECT_DOUBLE_EQ(*declaration(*back.actuator, "delay").upper, 0.05);
  // Starting from the file, the fit is where the first one ended.
  const FitResult again = fit_channel(
      fit_declared(signals_, split_, back.actuator->effects, {}, back.actuator->parameters),
      signals_, split_);
  EXPECT_NEAR(again.heldout_error, fit.heldout_error, 1e-6);
}

TEST(DeclaredModelWriteTest, ASpecimenIsWrittenAsItsKindAndTheEffectsBeside) {
  ChannelModel specimen;
  specimen.channel = Channel::kForce;
  specimen.effects = {Effect::kStiffness, Effect::kDelay, Effect::kDamping, Effect::kBoucWen};
  specimen.params = {1000.0, 0.001, 50.0, 20.0, 0.002};
  const config::DeclaredModel written = to_config(nullptr, &specimen);
  EXPECT_FALSE(written.has_actuator());
  EXPECT_EQ(written.specimen().kind(), "mr_damper");
  ASSERT_EQ(written.specimen().effects_size(), 1);
  EXPECT_EQ(written.specimen().effects(0), "delay");
  std::string text;
  ASSERT_TRUE(google::protobuf::TextFormat::PrintToString(written, &text));
  const DeclaredModel back = parse_declared_model(text, "written");
  EXPECT_DOUBLE_EQ(*declaration(*back.specimen, "yield_drift").initial, 0.002);
  EXPECT_DOUBLE_EQ(*declaration(*back.specimen, "delay").initial, 0.001);
}

}  // namespace
}  // namespace rths::identify
