#include "core/study.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace rths::core {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(RTHS_SOURCE_DIR) / "configs";

std::string error_of(const std::string& text) {
  try {
    parse_study(text, "test.textproto");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(StudyTest, PaperFrameConfigPreparesAtOneMillisecond) {
  const config::Study study = load_study(kConfigs / "paper_frame.textproto");
  const PreparedStudy prepared = prepare_study(study, kConfigs);
  EXPECT_DOUBLE_EQ(prepared.base.dt, 0.001);
  EXPECT_NEAR(prepared.motion.duration(), 7814 * 0.005, 0.01);
  EXPECT_EQ(prepared.base.partition.actuator_storeys.size(), 1u);
  EXPECT_NEAR(2 * M_PI / std::sqrt(prepared.base.model.stiffness(0, 0) / prepared.base.model.mass(0, 0)), 0.5, 1e-12);
  ASSERT_GE(study.cases_size(), 2);
  const HybridSetup lagged = setup_for_case(prepared, study.cases(1));
  ASSERT_EQ(lagged.delays.size(), 1u);
  EXPECT_DOUBLE_EQ(lagged.delays[0].nominal_delay(), 0.014);
  EXPECT_EQ(reference_case(study).name(), "reference");
}

TEST(StudyTest, UnknownFieldIsReportedWithLineAndColumn) {
  const std::string error = error_of("name: \"x\"\nstructure { sdof { period: 0.5 periodd: 2 } }\n");
  EXPECT_NE(error.find("test.textproto:2:"), std::string::npos) << error;
  EXPECT_NE(error.find("periodd"), std::string::npos) << error;
}

TEST(StudyTest, WrongTypeIsReported) {
  const std::string error = error_of("structure { sdof { period: \"half\" } }\n");
  EXPECT_NE(error.find("test.textproto:1:"), std::string::npos) << error;
}

TEST(StudyTest, SemanticErrorsNameTheField) {
  EXPECT_NE(error_of("structure { sdof { period: -0.5 } }").find("structure.sdof.period"), std::string::npos);
  EXPECT_NE(error_of("structure { sdof { period: 0.5 } } cases { name: \"a\" delay { shift { delay: -0.01 } } }")
                .find("delay[0].shift.delay"),
            std::string::npos);
  EXPECT_NE(error_of("structure { shear_building { storey_mass: 1 storey_stiffness: 1 } } "
                     "substructuring { experimental_fraction: 0.5 experimental_storeys: 1 }")
                .find("not both"),
            std::string::npos);
  EXPECT_NE(error_of("motion { path: \"x\" }").find("structure is missing"), std::string::npos);
  EXPECT_NE(error_of("structure { sdof { period: 0.5 } } cases { name: \"a\" delay { } }").find("has no kind"),
            std::string::npos);
}

TEST(StudyTest, MissingMotionFileIsNamed) {
  const config::Study study = parse_study("structure { sdof { period: 0.5 } } motion { path: \"nowhere.AT2\" }", "t");
  try {
    prepare_study(study, "/tmp");
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("nowhere.AT2"), std::string::npos) << e.what();
  }
}

TEST(StudyTest, SdofFromPeriodAndStiffnessDerivesMass) {
  config::Structure s;
  s.mutable_sdof()->set_period(0.5);
  s.mutable_sdof()->set_stiffness(2e6);
  s.mutable_damping()->set_modal_zeta(0.05);
  const StructuralModel model = make_structure(s);
  EXPECT_NEAR(model.mass(0, 0), 2e6 * 0.25 / (4 * M_PI * M_PI), 1e-9);
  const StructuralModel unit = make_structure([] {
    config::Structure u;
    u.mutable_sdof()->set_period(0.5);
    u.mutable_damping()->set_modal_zeta(0.05);
    return u;
  }());
  EXPECT_EQ(unit.damping(0, 0), make_sdof(0.5, 0.05).damping(0, 0));
}

TEST(StudyTest, EveryDelayKindBuildsAStage) {
  const config::Study study = parse_study(R"pb(
    structure { sdof { period: 0.5 } }
    cases {
      name: "all"
      delay { shift { delay: 0.01 } }
      delay { eq1 { delay: 0.01 } }
      delay { eq1_lag { delay: 0.01 } amplitude_gain: 0.9 }
      delay { first_order { time_constant: 0.01 } }
      delay { benchmark {} }
      delay { transfer_function { numerator: 1 denominator: [0.01, 1] } }
      delay { jitter { mean_delay: 0.01 std_dev: 0.001 seed: 7 } }
    })pb", "all");
  const DelayChain chain = make_delay_chain(study.cases(0).delay(), 0.001, ".");
  EXPECT_FALSE(chain.empty());
  EXPECT_NE(chain.describe().find("shift"), std::string::npos) << chain.describe();
}

}  // namespace
}  // namespace rths::core

namespace rths::core {
namespace {

TEST(StudyTest, ThreeStoreyBuildingConfigRunsEveryCase) {
  const config::Study study = load_study(kConfigs / "three_storey_building.textproto");
  const PreparedStudy prepared = prepare_study(study, kConfigs);
  EXPECT_EQ(prepared.base.model.dofs(), 3);
  EXPECT_EQ(prepared.base.partition.actuator_storeys, (std::vector<int>{0}));
  EXPECT_NEAR(prepared.motion.duration(), 15.0, 1e-9);
  double reference_peak = 0;
  for (const config::Case& c : study.cases()) {
    const SimulationResult r = simulate(setup_for_case(prepared, c), prepared.motion);
    EXPECT_FALSE(r.diverged) << c.name();
    const double peak = r.displacement.col(2).cwiseAbs().maxCoeff();
    if (c.name() == "reference") reference_peak = peak;
    EXPECT_GT(peak, 0.0);
    // The first storey yields: its drift exceeds the yield drift somewhere.
    EXPECT_GT(r.displacement.col(0).cwiseAbs().maxCoeff(), 0.004) << c.name();
  }
  EXPECT_GT(reference_peak, 0.0);
}

}  // namespace
}  // namespace rths::core
