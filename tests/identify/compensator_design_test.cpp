#include "identify/lab/compensator_design.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "study/compensation_config.h"
#include "study/study.h"

namespace rths::identify {
namespace {

constexpr double kDt = 1e-3;

// The identified MTS actuator: gain 1, 4.6 ms delay, 21.8 ms first order.
ChannelModel mts(double gain = 1.0) {
  ChannelModel m;
  m.channel = Channel::kMeasured;
  m.effects = {Effect::kDelay, Effect::kFirstOrder};
  m.params = {gain, 0.0046, 0.0218};
  return m;
}

TEST(CompensatorDesign, ModelBasedInvertsTheIdentifiedActuator) {
  const CompensatorDesign d =
      design_compensator(mts(), SignalScales{}, CompensatorKind::kModelBased, kDt);
  EXPECT_NEAR(d.plant_lag, 0.0264, 1e-12);
  EXPECT_DOUBLE_EQ(d.plant.delay, 0.0046);
  ASSERT_EQ(d.study_case.delay_size(), 2);
  EXPECT_DOUBLE_EQ(d.study_case.delay(1).first_order().time_constant(), 0.0218);
  ASSERT_EQ(d.study_case.compensation_size(), 1);
  const auto& m = d.study_case.compensation(0).model_based();
  EXPECT_EQ(m.plant_size(), 2);
  EXPECT_EQ(m.lead_order(), 2);
  EXPECT_GT(m.rolloff_frequency(), 0.0);
}

TEST(CompensatorDesign, ModelBasedAdaptiveAddsACorrectionBoundedByTheIdentifiedLag) {
  EXPECT_EQ(parse_compensator_kind("model-based-adaptive"), CompensatorKind::kAdaptedModelBased);
  const CompensatorDesign d =
      design_compensator(mts(), SignalScales{}, CompensatorKind::kAdaptedModelBased, kDt);
  EXPECT_EQ(d.study_case.name(), "identified_model-based-adaptive");
  const auto& m = d.study_case.compensation(0).model_based();
  EXPECT_EQ(m.plant_size(), 2);
  ASSERT_TRUE(m.has_adaptive_correction());
  const auto& a = m.adaptive_correction();
  EXPECT_DOUBLE_EQ(a.window(), 1.0);
  EXPECT_NEAR(a.a1_bounds().min(), -0.0264, 1e-12);
  EXPECT_NEAR(a.a1_bounds().max(), 0.0264, 1e-12);
  EXPECT_NEAR(a.a2_bounds().max(), 0.0264 * 0.0264, 1e-15);
  EXPECT_NE(d.summary.find("adaptive correction"), std::string::npos) << d.summary;
  const auto block = study::make_compensator(d.study_case.compensation(0), kDt, "designed");
  EXPECT_NE(dynamic_cast<const core::AdaptedModelBasedInverse*>(block.get()), nullptr);
  // The plain model-based design has no correction.
  EXPECT_FALSE(design_compensator(mts(), SignalScales{}, CompensatorKind::kModelBased, kDt)
                   .study_case.compensation(0)
                   .model_based()
                   .has_adaptive_correction());
}

TEST(CompensatorDesign, AtsAndPolynomialStartFromTheIdentifiedLag) {
  const auto ats =
      design_compensator(mts(0.95), SignalScales{}, CompensatorKind::kAdaptiveTimeSeries, kDt);
  const auto& a = ats.study_case.compensation(0).adaptive_time_series();
  EXPECT_NEAR(a.initial_a0(), 1.0 / 0.95, 1e-12);
  EXPECT_NEAR(a.initial_a1(), 0.0264, 1e-12);
  EXPECT_NEAR(a.initial_a2(), 0.0046 * 0.0218 + 0.5 * 0.0046 * 0.0046, 1e-15);
  EXPECT_DOUBLE_EQ(ats.study_case.delay(0).amplitude_gain(), 0.95);
  const auto poly = design_compensator(mts(), SignalScales{}, CompensatorKind::kPolynomial, kDt);
  EXPECT_NEAR(poly.study_case.compensation(0).polynomial().lead(), 0.0264, 1e-12);
  EXPECT_NEAR(poly.study_case.compensation(0).polynomial().spacing(), 0.013, 1e-12);
}

TEST(CompensatorDesign, NoActuatorModelIsAnErrorNotASilentFallBack) {
  ChannelModel gain_only;
  gain_only.channel = Channel::kMeasured;
  gain_only.params = {1.0};
  for (auto kind : {CompensatorKind::kModelBased, CompensatorKind::kAdaptedModelBased,
                    CompensatorKind::kPolynomial, CompensatorKind::kAdaptiveTimeSeries}) {
    try {
      design_compensator(gain_only, SignalScales{}, kind, kDt);
      FAIL() << "designed from no actuator model";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("no actuator delay or dynamics"), std::string::npos)
          << e.what();
    }
  }
  ChannelModel force;
  force.channel = Channel::kForce;
  EXPECT_THROW(design_compensator(force, SignalScales{}, CompensatorKind::kModelBased, kDt),
               std::invalid_argument);
  EXPECT_THROW(parse_compensator_kind("pid"), std::invalid_argument);
}

TEST(CompensatorDesign, WrittenCaseAppendsToAStudyAndRuns) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_comp_design_" + std::to_string(getpid()));
  const auto d = design_compensator(mts(), SignalScales{}, CompensatorKind::kModelBased, kDt);
  const auto path = write_compensator_case(d, dir);
  std::ifstream in(path);
  std::stringstream fragment;
  fragment << in.rdbuf();
  const std::string study =
      "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
      "motion { path: \"x.AT2\" }\nintegrator { dt: 0.001 }\n"
      "substructuring { experimental_fraction: 0.3333333333333333 }\ncases { name: \"reference\" "
      "}\n" +
      fragment.str();
  const config::Study parsed = study::parse_study(study, path.string());
  ASSERT_EQ(parsed.cases_size(), 2);
  EXPECT_EQ(parsed.cases(1).name(), "identified_model-based");
  EXPECT_EQ(parsed.cases(1).compensation(0).model_based().plant_size(), 2);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::identify
