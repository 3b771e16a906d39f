// The identified model as study-config parts: the actuator's delay stages, the specimen's storey
// restoring force (the same force as the identified model for the same drift history), and a
// whole study built from a base and the fragment, which runs.
#include "identify/model/study_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/simulation.h"
#include "study/study.h"
#include "study/text_format.h"

namespace rths::identify {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kData = RTHS_DATA_DIR;

// A drift history with growing amplitude: loops of several sizes, so hysteresis shows.
ChannelSignals drift_history() {
  ChannelSignals s;
  s.channel = Channel::kForce;
  s.dt = 0.001;
  for (int i = 0; i < 4000; ++i) {
    const double t = i * s.dt;
    s.time.push_back(t);
    s.input.push_back(0.004 * (0.2 + t / 4.0) * std::sin(2.0 * M_PI * 1.5 * t));
  }
  s.velocity.assign(s.size(), 0.0);
  s.acceleration.assign(s.size(), 0.0);
  s.target.assign(s.size(), 0.0);
  return s;
}

// The storey model of the restoring force at initial stiffness k0, stepped through the history.
std::vector<double> storey_forces(const config::RestoringForce& model, double k0,
                                  const ChannelSignals& s) {
  auto storey = study::make_storey_factory(model)(k0);
  std::vector<double> out;
  for (double d : s.input) out.push_back(storey->step(d));
  return out;
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  return worst;
}

ChannelModel force_model(std::vector<Effect> effects, std::vector<double> params) {
  ChannelModel m;
  m.channel = Channel::kForce;
  m.effects = std::move(effects);
  m.params = std::move(params);
  return m;
}

TEST(StudyConfigTest, TheActuatorBecomesShiftGainAndDynamicsStages) {
  ChannelModel a;
  a.channel = Channel::kMeasured;
  a.effects = {Effect::kDelay, Effect::kFirstOrder, Effect::kSecondOrder, Effect::kOffsetDrift};
  a.params = {0.97, 0.017, 0.006, 80.0, 0.6, 1e-4, 2e-5};
  const ActuatorCase c = actuator_case(a, SignalScales{});
  EXPECT_EQ(c.study_case.name(), kIdentifiedCaseName);
  ASSERT_EQ(c.study_case.delay_size(), 3);
  EXPECT_DOUBLE_EQ(c.study_case.delay(0).shift().delay(), 0.017);
  EXPECT_DOUBLE_EQ(c.study_case.delay(0).amplitude_gain(), 0.97);
  EXPECT_DOUBLE_EQ(c.study_case.delay(1).first_order().time_constant(), 0.006);
  const auto& tf = c.study_case.delay(2).transfer_function();
  EXPECT_DOUBLE_EQ(tf.numerator(0), 6400.0);
  EXPECT_DOUBLE_EQ(tf.denominator(1), 2.0 * 0.6 * 80.0);
  ASSERT_EQ(c.left_out.size(), 1u);
  EXPECT_THAT(c.left_out[0], HasSubstr("offset_drift"));
  EXPECT_THROW(actuator_case(force_model({Effect::kStiffness}, {1.0}), SignalScales{}),
               std::invalid_argument);
}

TEST(StudyConfigTest, ABoucWenSpecimenGivesTheSameForceAsTheStoreyModel) {
  const ChannelSignals s = drift_history();
  // k d + F_bw z with a yield drift of 1 mm, plus a dashpot that a storey model cannot carry.
  const ChannelModel m = force_model({Effect::kStiffness, Effect::kDamping, Effect::kBoucWen},
                                     {2.0e5, 300.0, 400.0, 0.001});
  const SpecimenModel sm = specimen_model(m, SignalScales{});
  ASSERT_TRUE(sm.restoring_force && sm.restoring_force->has_bouc_wen());
  EXPECT_DOUBLE_EQ(sm.initial_stiffness, 2.0e5 + 400.0 / 0.001);
  ASSERT_EQ(sm.left_out.size(), 1u);
  EXPECT_THAT(sm.left_out[0], HasSubstr("damping"));
  // Without the dashpot (velocity is zero in the history anyway) the forces agree.
  const auto identified = predict(m, s);
  const auto storey = storey_forces(*sm.restoring_force, sm.initial_stiffness, s);
  const double peak = 2.0e5 * 0.004 * 1.2 + 400.0;
  EXPECT_LT(max_abs_difference(identified, storey), 1e-3 * peak);
}

TEST(StudyConfigTest, AnElastoPlasticSpecimenGivesTheSameForceAsTheBilinearStorey) {
  const ChannelSignals s = drift_history();
  const ChannelModel m =
      force_model({Effect::kStiffness, Effect::kElastoPlastic}, {1.0e5, 4.0e5, 300.0});
  const SpecimenModel sm = specimen_model(m, SignalScales{});
  ASSERT_TRUE(sm.restoring_force && sm.restoring_force->has_bilinear());
  EXPECT_DOUBLE_EQ(sm.restoring_force->bilinear().yield_displacement(), 300.0 / 4.0e5);
  EXPECT_DOUBLE_EQ(sm.restoring_force->bilinear().post_yield_ratio(), 0.2);
  EXPECT_LT(max_abs_difference(predict(m, s),
                               storey_forces(*sm.restoring_force, sm.initial_stiffness, s)),
            1e-6);
}

TEST(StudyConfigTest, APureDamperHasNoStoreyModel) {
  const SpecimenModel sm = specimen_model(force_model({Effect::kDamping}, {500.0}), SignalScales{});
  EXPECT_FALSE(sm.restoring_force.has_value());
  EXPECT_THAT(sm.description, HasSubstr("no storey model"));
  const SpecimenModel spring =
      specimen_model(force_model({Effect::kStiffness}, {3.0e4}), SignalScales{});
  ASSERT_TRUE(spring.restoring_force && spring.restoring_force->has_linear());
  EXPECT_DOUBLE_EQ(spring.initial_stiffness, 3.0e4);
}

TEST(StudyConfigTest, AStudyBuiltFromTheFragmentRunsTheIdentifiedCase) {
  ChannelModel a;
  a.channel = Channel::kMeasured;
  a.effects = {Effect::kDelay, Effect::kFirstOrder};
  a.params = {1.0, 0.004, 0.003};
  const config::Study fragment = study_fragment(
      actuator_case(a, SignalScales{}),
      specimen_model(force_model({Effect::kStiffness, Effect::kBoucWen}, {2.0e4, 200.0, 0.002}),
                     SignalScales{}));
  // The fragment reads back as a Study.
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_study_config_test_" + std::to_string(getpid()));
  study::write_text_format(fragment, dir / "fragment.textproto", {"a comment line"});
  config::Study read_back;
  study::parse_text_format(study::read_text_file(dir / "fragment.textproto", "fragment"),
                           "fragment", read_back);
  EXPECT_EQ(read_back.DebugString(), fragment.DebugString());

  const config::Study base = study::parse_study(R"(
      name: "frame"
      structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }
      motion { path: "ground_motions/RSN175_IMPVALL.H_H-E12140.AT2" duration: 4 }
      integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }
      substructuring { experimental_fraction: 0.3 model { linear {} } }
      cases { name: "reference" }
      output { directory: "out/frame" })",
                                                "base");
  const config::Study study = identified_study(base, kData, read_back);
  EXPECT_EQ(study.name(), "frame_identified");
  EXPECT_TRUE(study.output().directory().empty());
  EXPECT_TRUE(std::filesystem::path(study.motion().path()).is_absolute());
  ASSERT_EQ(study.cases_size(), 2);
  EXPECT_EQ(study.cases(1).name(), kIdentifiedCaseName);
  ASSERT_TRUE(study.substructuring().model().has_bouc_wen());
  EXPECT_DOUBLE_EQ(study.substructuring().experimental_fraction(), 0.3);

  study::validate_study(study, "identified");
  const study::PreparedStudy prepared = study::prepare_study(study, dir);
  const core::SimulationResult reference =
      core::simulate(study::setup_for_case(prepared, study.cases(0)), prepared.motion);
  const core::SimulationResult identified =
      core::simulate(study::setup_for_case(prepared, study.cases(1)), prepared.motion);
  EXPECT_FALSE(identified.diverged);
  ASSERT_EQ(identified.steps(), reference.steps());
  // The identified actuator's 7 ms of lag shows in the realised displacement.
  double command_gap = 0.0;
  for (std::size_t i = 0; i < identified.steps(); ++i) {
    command_gap =
        std::max(command_gap, std::abs(identified.command(static_cast<Eigen::Index>(i), 0) -
                                       identified.realised(static_cast<Eigen::Index>(i), 0)));
  }
  EXPECT_GT(command_gap, 0.0);

  EXPECT_THAT(
      [&] {
        try {
          identified_study(study, kData, read_back);
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
        return std::string("no error");
      }(),
      HasSubstr("already has a case named 'identified_actuator'"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::identify

namespace rths::identify {
namespace {

// What the load cell reads beside the storey model, as force stages in the model's order, after
// the stages that move the specimen and before the sensor_drift that ends the case; an effect
// the case's stages already hold is not added again, and none is named as left out for want of a
// place.
TEST(StudyConfigTest, AFittedMassFrictionAndLateLoadCellBecomeForceStages) {
  ChannelModel m;
  m.channel = Channel::kForce;
  m.effects = {Effect::kStiffness, Effect::kDelay, Effect::kCoulomb, Effect::kInertia};
  m.params = {5.0e4, 0.004, 120.0, 0.003, 80.0};
  config::Case c;
  c.add_delay()->mutable_shift()->set_delay(0.014);
  c.add_delay()->mutable_sensor_drift()->set_displacement_offset(0.001);
  config::Case all = c;
  add_force_stages(m, SignalScales{}, RigRecord{}, all);
  ASSERT_EQ(all.delay_size(), 5);
  EXPECT_DOUBLE_EQ(all.delay(0).shift().delay(), 0.014);
  EXPECT_DOUBLE_EQ(all.delay(1).friction_force().friction_force(), 120.0);
  EXPECT_DOUBLE_EQ(all.delay(1).friction_force().smoothing_velocity(), 0.003);
  EXPECT_DOUBLE_EQ(all.delay(2).inertia_force().mass(), 80.0);
  EXPECT_DOUBLE_EQ(all.delay(3).force_delay().delay(), 0.004);
  EXPECT_TRUE(all.delay(4).has_sensor_drift());
  config::Case held = c;
  add_force_stages(m, SignalScales{}, RigRecord{}, held, {Effect::kInertia, Effect::kDelay});
  ASSERT_EQ(held.delay_size(), 3);
  EXPECT_TRUE(held.delay(1).has_friction_force());
  for (const auto& note : specimen_model(m, SignalScales{}).left_out)
    EXPECT_THAT(note, ::testing::Not(::testing::HasSubstr("no place"))) << note;
  for (Effect e : {Effect::kDamping, Effect::kCoulomb, Effect::kInertia, Effect::kDelay})
    EXPECT_TRUE(held_by_force_stages(e)) << effect_name(e);
  EXPECT_FALSE(held_by_force_stages(Effect::kCubicStiffness));
}

}  // namespace
}  // namespace rths::identify
