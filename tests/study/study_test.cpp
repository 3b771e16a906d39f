#include "study/study.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace rths::study {
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
  EXPECT_NEAR(
      2 * M_PI / std::sqrt(prepared.base.model.stiffness(0, 0) / prepared.base.model.mass(0, 0)),
      0.5, 1e-12);
  ASSERT_GE(study.cases_size(), 2);
  const core::HybridSetup lagged = setup_for_case(prepared, study.cases(1));
  ASSERT_EQ(lagged.delays.size(), 1u);
  EXPECT_DOUBLE_EQ(lagged.delays[0].nominal_delay(), 0.014);
  EXPECT_EQ(reference_case(study).name(), "reference");
  // One way to find a case: by name, the reference when the name is empty, else named as absent.
  EXPECT_EQ(find_case(study, "").name(), "reference");
  EXPECT_EQ(find_case(study, study.cases(1).name()).name(), study.cases(1).name());
  EXPECT_EQ(case_named(study, "no such case"), nullptr);
  try {
    find_case(study, "no such case");
    ADD_FAILURE() << "an absent case was found";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "case 'no such case' is not among the study's cases");
  }
}

TEST(StudyTest, UnknownFieldIsReportedWithLineAndColumn) {
  const std::string error =
      error_of("name: \"x\"\nstructure { sdof { period: 0.5 periodd: 2 } }\n");
  EXPECT_NE(error.find("test.textproto:2:"), std::string::npos) << error;
  EXPECT_NE(error.find("periodd"), std::string::npos) << error;
}

TEST(StudyTest, WrongTypeIsReported) {
  const std::string error = error_of("structure { sdof { period: \"half\" } }\n");
  EXPECT_NE(error.find("test.textproto:1:"), std::string::npos) << error;
}

TEST(StudyTest, SemanticErrorsNameTheField) {
  EXPECT_NE(error_of("structure { sdof { period: -0.5 } }").find("structure.sdof.period"),
            std::string::npos);
  EXPECT_NE(error_of("structure { sdof { period: 0.5 } } cases { name: \"a\" delay { shift { "
                     "delay: -0.01 } } }")
                .find("delay[0].shift.delay"),
            std::string::npos);
  EXPECT_NE(error_of("structure { shear_building { storey_mass: 1 storey_stiffness: 1 } } "
                     "substructuring { experimental_fraction: 0.5 experimental_storeys: 1 }")
                .find("not both"),
            std::string::npos);
  EXPECT_NE(error_of("motion { path: \"x\" }").find("structure is missing"), std::string::npos);
  EXPECT_NE(error_of("structure { sdof { period: 0.5 } } cases { name: \"a\" delay { } }")
                .find("has no kind"),
            std::string::npos);
}

TEST(StudyTest, MissingMotionFileIsNamed) {
  const config::Study study =
      parse_study("structure { sdof { period: 0.5 } } motion { path: \"nowhere.AT2\" }", "t");
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
  const core::StructuralModel model = make_structure(s);
  EXPECT_NEAR(model.mass(0, 0), 2e6 * 0.25 / (4 * M_PI * M_PI), 1e-9);
  const core::StructuralModel unit = make_structure([] {
    config::Structure u;
    u.mutable_sdof()->set_period(0.5);
    u.mutable_damping()->set_modal_zeta(0.05);
    return u;
  }());
  EXPECT_EQ(unit.damping(0, 0), core::make_sdof(0.5, 0.05).damping(0, 0));
}

TEST(StudyTest, AZeroMassIsRefusedNamingItsFieldNotRunAsADefault) {
  for (const char* text :
       {"structure { sdof { period: 0.5 mass: 0 } }", "structure { sdof { period: 0.5 mass: -2 } }",
        "structure { sdof { mass: 0 stiffness: 1000 } }"}) {
    const std::string error = error_of(text);
    EXPECT_NE(error.find("structure.sdof.mass must be > 0 kg"), std::string::npos) << text;
  }
  EXPECT_NE(error_of("structure { sdof { period: 0.5 mass: 5 stiffness: 1000 } }")
                .find("mass, period and stiffness are all given"),
            std::string::npos);
  EXPECT_NE(
      error_of("structure { shear_building { storey_mass: [1, 0] storey_stiffness: [1, 1] } }")
          .find("structure.shear_building.storey_mass[1] must be > 0 kg"),
      std::string::npos);
  // Omitted, the mass is 1 kg (what the config reference says); given, it is used.
  EXPECT_EQ(error_of("structure { sdof { period: 0.5 } }").find("mass"), std::string::npos);
  config::Structure given;
  given.mutable_sdof()->set_period(0.5);
  given.mutable_sdof()->set_mass(250);
  given.mutable_damping()->set_modal_zeta(0.05);
  EXPECT_EQ(make_structure(given).mass(0, 0), 250);
}

TEST(StudyTest, EveryDelayKindBuildsAStage) {
  const config::Study study =
      parse_study(R"pb(
                    structure { sdof { period: 0.5 } }
                    cases {
                      name: "all"
                      delay { shift { delay: 0.01 } }
                      delay { eq1 { delay: 0.01 } }
                      delay {
                        eq1_lag { delay: 0.01 }
                        amplitude_gain: 0.9
                      }
                      delay { first_order { time_constant: 0.01 } }
                      delay { benchmark {} }
                      delay {
                        transfer_function {
                          numerator: 1
                          denominator: [ 0.01, 1 ]
                        }
                      }
                      delay { jitter { mean_delay: 0.01 std_dev: 0.001 seed: 7 } }
                      delay { backlash { width: 0.001 } }
                      delay { velocity_limit { max_velocity: 0.2 } }
                      delay { sensor_drift { force_offset: 10 } }
                      delay { viscous_force { damping: 300 } }
                      delay { inertia_force { mass: 20 } }
                      delay { friction_force { friction_force: 50 smoothing_velocity: 0.001 } }
                      delay { force_delay { delay: 0.002 } }
                    })pb",
                  "all");
  const core::DelayChain chain = make_delay_chain(study.cases(0).delay(), 0.001, ".");
  EXPECT_FALSE(chain.empty());
  for (const char* kind : {"shift", "jitter", "backlash", "velocity_limit", "sensor_drift",
                           "viscous_force", "inertia_force", "friction_force", "force_delay"})
    EXPECT_NE(chain.describe().find(kind), std::string::npos) << chain.describe();
}

}  // namespace
}  // namespace rths::study

namespace rths::study {
namespace {

TEST(StudyTest, ThreeStoreyBuildingConfigRunsEveryCase) {
  const config::Study study = load_study(kConfigs / "three_storey_building.textproto");
  const PreparedStudy prepared = prepare_study(study, kConfigs);
  EXPECT_EQ(prepared.base.model.dofs(), 3);
  EXPECT_EQ(prepared.base.partition.actuator_storeys, (std::vector<int>{0}));
  EXPECT_NEAR(prepared.motion.duration(), 15.0, 1e-9);
  double reference_peak = 0;
  for (const config::Case& c : study.cases()) {
    const core::SimulationResult r = core::simulate(setup_for_case(prepared, c), prepared.motion);
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
}  // namespace rths::study

namespace rths::study {
namespace {

TEST(StudyBounds, AbsurdValuesAreRefusedNamingTheField) {
  // zeta = 5 is 500 % of critical: a ratio was meant (0.05).
  const std::string zeta = error_of("structure { sdof { period: 0.5 } damping { modal_zeta: 5 } }");
  EXPECT_NE(zeta.find("structure.damping.modal_zeta"), std::string::npos) << zeta;
  EXPECT_NE(zeta.find("0.05 = 5 %"), std::string::npos) << zeta;
  // delay: 14 is 14 s: milliseconds were meant.
  const std::string delay = error_of(
      "structure { sdof { period: 0.5 } } cases { name: \"a\" delay { shift { delay: 14 } } }");
  EXPECT_NE(delay.find("delay[0].shift.delay"), std::string::npos) << delay;
  EXPECT_NE(delay.find("14 ms is 0.014"), std::string::npos) << delay;
  EXPECT_NE(
      error_of("structure { sdof { period: 0.5 } } integrator { dt: 2 }").find("integrator.dt"),
      std::string::npos);
  EXPECT_NE(error_of("structure { sdof { period: 500 } }").find("structure.sdof.period"),
            std::string::npos);
  EXPECT_NE(error_of("structure { sdof { period: 0.5 } } sweep { delays: [0.01, 12] }")
                .find("sweep.delays"),
            std::string::npos);
  EXPECT_NE(
      error_of("structure { sdof { period: 0.5 } } deployment { limits { max_displacement: -1 } }")
          .find("deployment.limits"),
      std::string::npos);
}

TEST(StudyServo, TheServoRateIsAWholeMultipleOfTheIntegratorRate) {
  const auto study = [](const std::string& servo) {
    return parse_study("structure { sdof { period: 0.5 } } " + servo, "t");
  };
  EXPECT_EQ(servo_substeps(study(""), 1.0 / 1024), 1);
  EXPECT_EQ(servo_substeps(study("servo { rate: 4096 }"), 1.0 / 1024), 4);
  EXPECT_EQ(servo_substeps(study("servo { rate: 1024 }"), 1.0 / 1024), 1);
  const core::HybridSetup base = base_setup(
      study("servo { rate: 4000 } substructuring { experimental_fraction: 0.5 }"), 0.001);
  EXPECT_EQ(base.servo_substeps, 4);
  for (const char* bad : {"servo { rate: 3000 }", "servo { rate: 500 }", "servo { rate: 1e6 }"}) {
    try {
      servo_substeps(study(bad), 1.0 / 1024);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("servo.rate"), std::string::npos) << e.what();
    }
  }
  EXPECT_NE(error_of("structure { sdof { period: 0.5 } } servo { rate: -4096 }").find("servo.rate"),
            std::string::npos);
}

TEST(StudyServo, ACaseChainRunsAtTheServoPeriod) {
  const config::Study study = load_study(kConfigs / "paper_frame.textproto");
  config::Study fast = study;
  fast.mutable_servo()->set_rate(4000);
  const PreparedStudy prepared = prepare_study(fast, kConfigs);
  EXPECT_EQ(prepared.base.servo_substeps, 4);
  const core::HybridSetup lagged = setup_for_case(prepared, fast.cases(1));
  ASSERT_EQ(lagged.delays.size(), 1u);
  // 14 ms is 56 servo periods of 0.25 ms: the same lag in seconds.
  EXPECT_DOUBLE_EQ(lagged.delays[0].nominal_delay(), 0.014);
}

TEST(StudyBounds, DuplicateCaseNamesAreRefused) {
  const std::string error = error_of(
      "structure { sdof { period: 0.5 } } cases { name: \"a\" } cases { name: \"b\" } cases { "
      "name: \"a\" }");
  EXPECT_NE(error.find("cases[2] repeats the name 'a'"), std::string::npos) << error;
}

TEST(StudyBounds, ADelayLongerThanTheRecordIsRefused) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rths_study_long_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "short.txt") << "0 0\n0.01 0.1\n0.02 0\n0.03 -0.1\n0.04 0\n";
  const config::Study study = parse_study(
      "structure { sdof { period: 0.5 } } motion { path: \"short.txt\" column_units: G } "
      "substructuring { experimental_fraction: 0.5 } cases { name: \"ref\" } "
      "cases { name: \"late\" delay { shift { delay: 0.2 } } }",
      "t");
  try {
    prepare_study(study, dir);
    FAIL() << "a 0.2 s delay on a 0.05 s record was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("case 'late'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not shorter than the record"), std::string::npos)
        << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(StudyBounds, AForcePredictorOutOfRangeIsRefusedNamingTheField) {
  const auto refusal = [](const std::string& block) {
    return error_of(
        "structure { sdof { period: 0.5 } } motion { path: \"m.txt\" column_units: G } "
        "integrator { dt: 0.001 } substructuring { experimental_fraction: 0.5 } "
        "cases { name: \"ref\" } cases { name: \"remote\" force_predictor { " +
        block + " } }");
  };
  EXPECT_EQ(refusal("max_relative_error: 0.5"), "");
  EXPECT_NE(refusal("actuators: 0").find("cases[1] 'remote' force_predictor.actuators[0] = 0"),
            std::string::npos)
      << refusal("actuators: 0");
  EXPECT_NE(refusal("actuators: 1 actuators: 1").find("repeats actuator 1"), std::string::npos);
  EXPECT_NE(refusal("stiffness_factor: -0.3").find("force_predictor.stiffness_factor"),
            std::string::npos);
  EXPECT_NE(refusal("forgetting_time: -1").find("force_predictor.forgetting_time"),
            std::string::npos);
  EXPECT_NE(refusal("max_relative_error: -0.1").find("force_predictor.max_relative_error"),
            std::string::npos);
  EXPECT_NE(refusal("error_window: 0.0001").find("shorter than one step"), std::string::npos);
  EXPECT_NE(refusal("force_lag: -0.003").find("force_predictor.force_lag"), std::string::npos);
  EXPECT_NE(refusal("model { bouc_wen { yield_displacement: 0 } }")
                .find("force_predictor.model.bouc_wen.yield_displacement must be > 0 m"),
            std::string::npos);
  EXPECT_NE(refusal("linear_model: true model { bilinear { yield_displacement: 0.01 } }")
                .find("linear_model: true asks for none"),
            std::string::npos);
  // An actuator the study does not have is named when the case is set up.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rths_study_pred_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "m.txt") << "0 0\n0.01 0.1\n0.02 0\n0.03 -0.1\n0.04 0\n";
  const PreparedStudy prepared = prepare_study(
      parse_study("structure { sdof { period: 0.5 } } motion { path: \"m.txt\" column_units: G } "
                  "substructuring { experimental_fraction: 0.5 } cases { name: \"ref\" } "
                  "cases { name: \"remote\" force_predictor { actuators: 2 } }",
                  "t"),
      dir);
  try {
    setup_for_case(prepared, find_case(prepared.config, "remote"));
    FAIL() << "a predictor on actuator 2 of a study with one was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("force_predictor.actuators names actuator 2 but the "
                                         "study has 1"),
              std::string::npos)
        << e.what();
  }
  std::filesystem::remove_all(dir);
}

// The setup of case "remote" of an SDOF study (0.5 s, 1000 kg, half of it experimental) whose
// force_predictor block is `block` (text format), prepared on a short motion in a directory of its
// own (`tag`), removed again.
core::HybridSetup predicted_sdof_setup(const std::string& block, const std::string& tag) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("rths_study_" + tag + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "m.txt") << "0 0\n0.01 0.1\n0.02 0\n0.03 -0.1\n0.04 0\n";
  const PreparedStudy prepared = prepare_study(
      parse_study("structure { sdof { period: 0.5 mass: 1000 } } "
                  "motion { path: \"m.txt\" column_units: G } "
                  "substructuring { experimental_fraction: 0.5 } cases { name: \"ref\" } "
                  "cases { name: \"remote\" force_predictor { " +
                      block + " } }",
                  "t"),
      dir);
  core::HybridSetup setup = setup_for_case(prepared, find_case(prepared.config, "remote"));
  std::filesystem::remove_all(dir);
  return setup;
}

// A ForcePredictor block's defaults are read in one place (predictor_stiffness_factor,
// predictor_parameters): unset fields give PredictorParameters' own, stiffness_factor unset is 1,
// and the case's setup starts each predictor there.
TEST(StudyBounds, AForcePredictorsDefaultsAreReadInOnePlace) {
  const config::ForcePredictor unset;
  const core::PredictorParameters defaults;
  EXPECT_EQ(predictor_stiffness_factor(unset), 1.0);
  const core::PredictorParameters plain = predictor_parameters(unset, 2.0e6);
  EXPECT_EQ(plain.stiffness, 2.0e6);
  EXPECT_EQ(plain.damping, 0.0);
  EXPECT_TRUE(plain.adapt);
  EXPECT_EQ(plain.forgetting_time, defaults.forgetting_time);
  EXPECT_EQ(plain.min_displacement, defaults.min_displacement);
  EXPECT_EQ(plain.error_window, defaults.error_window);
  EXPECT_TRUE(plain.specimen_shape);
  config::ForcePredictor set;
  set.set_stiffness_factor(1.25);
  set.set_damping(40.0);
  set.set_fixed_model(true);
  set.set_forgetting_time(0.5);
  EXPECT_EQ(predictor_stiffness_factor(set), 1.25);
  const core::PredictorParameters given = predictor_parameters(set, 2.0e6);
  EXPECT_EQ(given.stiffness, 2.5e6);
  EXPECT_EQ(given.damping, 40.0);
  EXPECT_FALSE(given.adapt);
  EXPECT_EQ(given.forgetting_time, 0.5);
  const core::HybridSetup setup = predicted_sdof_setup("stiffness_factor: 1.25", "pred_default");
  ASSERT_EQ(setup.predictors.size(), 1u);
  ASSERT_TRUE(setup.predictors[0].has_value());
  const double declared = setup.partition.experimental[0]->initial_stiffness();
  EXPECT_GT(declared, 0.0);
  EXPECT_DOUBLE_EQ(setup.predictors[0]->stiffness, 1.25 * declared);
}

// force_predictor.model (a Bouc-Wen rths identify fitted) is the predictor's shape at the declared
// specimen's initial stiffness, the declared (linear) specimen staying what runs; force_lag is
// its lag term's start.
TEST(StudyBounds, AForcePredictorsOwnModelIsItsShape) {
  const core::HybridSetup setup = predicted_sdof_setup(
      "force_lag: 0.003 model { bouc_wen { yield_displacement: 0.002 alpha: 0.1 } }", "shape");
  ASSERT_EQ(setup.predictors.size(), 1u);
  ASSERT_TRUE(setup.predictors[0].has_value());
  const core::PredictorParameters& p = *setup.predictors[0];
  ASSERT_NE(p.shape, nullptr);
  EXPECT_EQ(p.shape->initial_stiffness(), p.stiffness);
  EXPECT_EQ(p.force_lag, 0.003);
  const core::ForcePredictor predictor(p, 0.001, "remote", setup.partition.experimental[0].get());
  EXPECT_TRUE(predictor.hysteretic());
  EXPECT_NEAR(predictor.model().stiffness, 0.1 * p.stiffness, 1e-9 * p.stiffness);
  EXPECT_NEAR(predictor.model().hysteretic, 0.9 * p.stiffness * 0.002, 1e-9 * p.stiffness);
  EXPECT_EQ(predictor.model().force_lag, 0.003);
}

// The config's integrator kinds and core's map one to one, both ways (the `sdof` command builds
// its study through the inverse).
TEST(StudyTest, EveryIntegratorKindMapsToTheConfigAndBack) {
  for (int k = config::Integrator::Kind_MIN; k <= config::Integrator::Kind_MAX; ++k) {
    config::Integrator integrator;
    integrator.set_kind(static_cast<config::Integrator::Kind>(k));
    EXPECT_EQ(config_integrator_kind(integrator_kind(integrator)), integrator.kind()) << k;
  }
  EXPECT_EQ(integrator_kind(config::Integrator{}), core::IntegratorKind::kExplicitNewmark);
}

// Every number of the deployment is checked when the study is parsed, by the range rules.
TEST(StudyTest, DeploymentNumbersAreRangeChecked) {
  const std::string base = "structure { sdof { period: 0.5 } } ";
  const std::string lag = error_of(
      base +
      "deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR send_lag { one_way_delay: 7 } } }");
  EXPECT_NE(lag.find("deployment.nodes[0].send_lag.one_way_delay = 7 s is outside [0, 1] s"),
            std::string::npos)
      << lag;
  EXPECT_NE(lag.find("allow_long_lag"), std::string::npos) << lag;
  EXPECT_EQ(
      error_of(base + "allow_long_lag: true deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR "
                      "send_lag { one_way_delay: 7 } } }"),
      "");
  EXPECT_NE(
      error_of(base +
               "deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR receive_lag { jitter: 5 } } }")
          .find("receive_lag.jitter = 5 s"),
      std::string::npos);
  EXPECT_NE(error_of(base + "deployment { max_missed_answers: -3 }")
                .find("deployment.max_missed_answers = -3"),
            std::string::npos);
  EXPECT_NE(error_of(base + "deployment { min_answer_fraction: 1.5 }")
                .find("deployment.min_answer_fraction"),
            std::string::npos);
  EXPECT_NE(error_of(base + "deployment { pin_loop: true loop_cpu: 99999 }")
                .find("deployment.loop_cpu = 99999"),
            std::string::npos);
  EXPECT_NE(error_of(base + "deployment { step_timeout: -1 }").find("deployment.step_timeout"),
            std::string::npos);
  EXPECT_NE(error_of(base + "deployment { clock: REAL_TIME realtime_priority: 99 }")
                .find("deployment.realtime_priority (0 or -1: off) = 99 is outside [1, 98]"),
            std::string::npos);
  EXPECT_NE(error_of(base + "deployment { realtime_priority: 80 }").find("clock: REAL_TIME only"),
            std::string::npos);
  EXPECT_NE(error_of(base + "deployment { clock: REAL_TIME realtime_priority: 80 "
                            "wait_policy: WAIT_SPIN }")
                .find("WAIT_SLEEP_THEN_SPIN"),
            std::string::npos);
  EXPECT_EQ(error_of(base + "deployment { clock: REAL_TIME realtime_priority: 80 }"), "");
  // -1 is off too, in any clock and wait policy; -2 is no priority.
  EXPECT_EQ(error_of(base + "deployment { clock: REAL_TIME realtime_priority: -1 "
                            "wait_policy: WAIT_SPIN }"),
            "");
  EXPECT_NE(error_of(base + "deployment { clock: REAL_TIME realtime_priority: -2 }")
                .find("is outside [1, 98]"),
            std::string::npos);
  EXPECT_NE(
      error_of(base + "cases { name: \"a\" delay { shift { delay: 2 } } }").find("allow_long_lag"),
      std::string::npos);
  EXPECT_EQ(
      error_of(base + "allow_long_lag: true cases { name: \"a\" delay { shift { delay: 2 } } }"),
      "");
  EXPECT_NE(error_of(base + "integrator { dt: 1e-9 }").find("integrator.dt"), std::string::npos);
}

}  // namespace
}  // namespace rths::study
