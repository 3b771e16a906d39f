#include "identify/fit/selection.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "identify/lab/generator.h"

namespace rths::identify {
namespace {

struct UndeclaredCase {
  std::string name;
  Channel channel;
  Effect expected;
  std::function<void(GeneratorSpec&)> add_effect;
  GeneratorSpec::Command command = GeneratorSpec::Command::kChirp;
};

ChannelIdentification run(const GeneratorSpec& spec, Channel channel) {
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, channel);
  const Split split = holdout_split(s.size(), 0.3, HoldoutMode::kBlocks);
  return identify_channel(s, split, default_declared(channel), SelectionOptions{});
}

class UndeclaredEffectTest : public ::testing::TestWithParam<UndeclaredCase> {};

TEST_P(UndeclaredEffectTest, NamesTheEffectFirstAndClosesMostOfTheGap) {
  const UndeclaredCase& c = GetParam();
  GeneratorSpec clean;
  clean.command = c.command;
  GeneratorSpec with_effect = clean;
  c.add_effect(with_effect);
  // The floor: what the declared model leaves on the same data without the effect (noise).
  const double floor = run(clean, c.channel).declared_fit.heldout_error;
  const ChannelIdentification id = run(with_effect, c.channel);
  ASSERT_FALSE(id.steps.empty()) << c.name;
  EXPECT_EQ(id.steps.front().effect, c.expected)
      << c.name << ": first step was " << effect_name(id.steps.front().effect);
  const double before = id.declared_fit.heldout_error;
  const double after = id.final_fit.heldout_error;
  EXPECT_GT(before, 2.0 * floor) << c.name << ": the effect must be visible";
  EXPECT_GT((before - after) / (before - floor), 0.8)
      << c.name << ": held-out " << before << " -> " << after << ", floor " << floor;
  for (const auto& step : id.steps) {
    EXPECT_LT(step.after.heldout_error, step.before.heldout_error) << "a step that does not pay";
  }
}

INSTANTIATE_TEST_SUITE_P(
    GeneratedSets, UndeclaredEffectTest,
    ::testing::Values(
        UndeclaredCase{"first_order", Channel::kMeasured, Effect::kFirstOrder,
                       [](GeneratorSpec& s) { s.first_order_time_constant = 0.015; }},
        UndeclaredCase{"offset", Channel::kMeasured, Effect::kOffsetDrift,
                       [](GeneratorSpec& s) { s.offset = 3e-4; },
                       GeneratorSpec::Command::kEarthquake},
        UndeclaredCase{"time_varying_delay", Channel::kMeasured, Effect::kTimeVaryingDelay,
                       [](GeneratorSpec& s) { s.delay_drift = 0.006; }},
        UndeclaredCase{"time_varying_stiffness", Channel::kForce, Effect::kTimeVaryingStiffness,
                       [](GeneratorSpec& s) { s.stiffness_drift = 0.2; }},
        UndeclaredCase{"time_varying_gain", Channel::kMeasured, Effect::kTimeVaryingGain,
                       [](GeneratorSpec& s) { s.gain_drift = 0.1; }},
        UndeclaredCase{"backlash", Channel::kMeasured, Effect::kBacklash,
                       [](GeneratorSpec& s) { s.backlash_width = 3e-4; }},
        UndeclaredCase{"coulomb", Channel::kForce, Effect::kCoulomb,
                       [](GeneratorSpec& s) { s.coulomb_force = 60.0; },
                       GeneratorSpec::Command::kEarthquake},
        UndeclaredCase{"cubic", Channel::kForce, Effect::kCubicStiffness,
                       [](GeneratorSpec& s) { s.cubic_stiffness = 1.5e10; }},
        UndeclaredCase{"damping", Channel::kForce, Effect::kDamping,
                       [](GeneratorSpec& s) { s.damping = 3000.0; },
                       GeneratorSpec::Command::kEarthquake}),
    [](const ::testing::TestParamInfo<UndeclaredCase>& info) { return info.param.name; });

class CleanDataTest : public ::testing::TestWithParam<GeneratorSpec::Command> {};

TEST_P(CleanDataTest, NothingIsAdded) {
  GeneratorSpec spec;
  spec.command = GetParam();
  spec.seed = 11;
  for (Channel channel : {Channel::kMeasured, Channel::kForce}) {
    const ChannelIdentification id = run(spec, channel);
    EXPECT_TRUE(id.steps.empty()) << channel_name(channel) << ": added "
                                  << effect_name(id.steps.front().effect);
    EXPECT_FALSE(id.last_ranking.empty());
    for (const auto& trial : id.last_ranking) EXPECT_FALSE(trial.pays);
  }
}

INSTANTIATE_TEST_SUITE_P(Commands, CleanDataTest,
                         ::testing::Values(GeneratorSpec::Command::kChirp,
                                           GeneratorSpec::Command::kEarthquake));

TEST(SelectionTest, RestrictedCandidatesAndMaxSteps) {
  GeneratorSpec spec;
  spec.first_order_time_constant = 0.015;
  spec.offset = 2e-4;
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kMeasured);
  const Split split = holdout_split(s.size(), 0.3, HoldoutMode::kBlocks);
  SelectionOptions options;
  options.candidates = {Effect::kBacklash, Effect::kOffsetDrift};
  options.max_steps = 1;
  const auto id = identify_channel(s, split, default_declared(Channel::kMeasured), options);
  ASSERT_EQ(id.steps.size(), 1u);
  EXPECT_EQ(id.steps[0].ranking.size(), 2u);
  EXPECT_EQ(id.steps[0].effect, Effect::kOffsetDrift);
}

// A damper whose force falls with displacement (c v - k d): the declared spring wants a negative
// stiffness; the tool says the kind is wrong, proposes the damper and never fits k < 0.
TEST(SelectionTest, WrongKindIsReportedAndABetterKindProposed) {
  GeneratorSpec spec;
  spec.command = GeneratorSpec::Command::kEarthquake;
  spec.stiffness = 0.0;
  MeasuredData data = generate_measured(spec);
  const ChannelSignals first = make_signals(data, Channel::kForce);
  for (std::size_t i = 0; i < data.size(); ++i) {
    data.force[i] = 3000.0 * first.velocity[i] - 5.0e4 * data.measured[i];
  }
  const ChannelSignals s = make_signals(data, Channel::kForce);
  const Split split = holdout_split(s.size(), 0.3, HoldoutMode::kBlocks);
  const auto id = identify_channel(s, split, {Effect::kStiffness}, SelectionOptions{});
  ASSERT_TRUE(id.kind.has_value());
  ASSERT_FALSE(id.kind->declared_hits.empty());
  EXPECT_EQ(id.kind->declared_hits.front().message(), "the data want a negative stiffness");
  ASSERT_TRUE(id.kind->proposed.has_value());
  EXPECT_EQ(*id.kind->proposed, SpecimenKind::kViscousDamper);
  EXPECT_TRUE(id.declared_search_final.has_value());
  const auto sc = signal_scales(s);
  EXPECT_GE(id.final_fit.model.param(Effect::kDamping, "damping", sc).value_or(0.0), 2500.0);
  EXPECT_GE(id.final_fit.model.param(Effect::kStiffness, "stiffness", sc).value_or(0.0), 0.0);
}

// An MR-damper-like specimen (dashpot + Bouc–Wen hysteresis, no spring): the kind comparison
// ranks the Spencer model first.
TEST(SelectionTest, KindComparisonRanksTheHystereticDamperFirst) {
  GeneratorSpec spec;
  spec.command = GeneratorSpec::Command::kEarthquake;
  spec.stiffness = 1.0e6;
  spec.bouc_wen_yield = 1e-4;
  spec.bouc_wen_alpha = 0.0;  // pure hysteresis of 100 N
  spec.damping = 4000.0;
  const MeasuredData data = generate_measured(spec);
  const ChannelSignals s = make_signals(data, Channel::kForce);
  const Split split = holdout_split(s.size(), 0.3, HoldoutMode::kBlocks);
  const KindProposal proposal = compare_kinds(s, split, {}, SelectionOptions{});
  ASSERT_TRUE(proposal.proposed.has_value());
  EXPECT_EQ(*proposal.proposed, SpecimenKind::kMrDamper);
  EXPECT_TRUE(is_hysteretic_damper(*proposal.proposed));
  EXPECT_EQ(proposal.ranking.size(), specimen_kinds().size());
}

struct EffectPair {
  std::string name;
  Effect first, second;
  std::function<void(GeneratorSpec&)> add;
};

// Two undeclared actuator effects at once, generated from core blocks: both named, each with its
// own part of the error removed, and those parts sum to one.
TEST(SelectionTest, TwoUndeclaredEffectsAreBothNamed) {
  const std::vector<EffectPair> pairs{
      {"first_order+offset", Effect::kFirstOrder, Effect::kOffsetDrift,
       [](GeneratorSpec& s) {
         s.first_order_time_constant = 0.015;
         s.offset = 2e-4;
       }},
      {"backlash+offset", Effect::kBacklash, Effect::kOffsetDrift,
       [](GeneratorSpec& s) {
         s.backlash_width = 3e-4;
         s.offset = 2e-4;
       }},
      {"first_order+backlash", Effect::kFirstOrder, Effect::kBacklash,
       [](GeneratorSpec& s) {
         s.first_order_time_constant = 0.015;
         s.backlash_width = 3e-4;
       }},
  };
  std::size_t both = 0;
  for (const auto& pair : pairs) {
    GeneratorSpec spec;
    spec.duration = 12.0;
    pair.add(spec);
    const ChannelIdentification id = run(spec, Channel::kMeasured);
    const bool named = id.final_fit.model.has(pair.first) && id.final_fit.model.has(pair.second);
    both += named ? 1 : 0;
    EXPECT_TRUE(named) << pair.name;
    double shares = 0.0;
    for (const auto& step : id.steps) {
      EXPECT_GT(step.own_error_removed, 0.0) << pair.name << " " << effect_name(step.effect);
      shares += step.own_share;
    }
    EXPECT_NEAR(shares, 1.0, 1e-9) << pair.name;
  }
  EXPECT_GE(static_cast<double>(both), 0.9 * static_cast<double>(pairs.size()));
}

TEST(SelectionTest, DefaultDeclaredModels) {
  EXPECT_EQ(default_declared(Channel::kMeasured), std::vector<Effect>{Effect::kDelay});
  EXPECT_EQ(default_declared(Channel::kForce), std::vector<Effect>{Effect::kStiffness});
}

}  // namespace
}  // namespace rths::identify
