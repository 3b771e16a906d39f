// A rig's own effects as delay stages (core/rig_effects.h): each recursion as its header states
// it (backlash, velocity and stroke limits), the sensors' errors, a viscous force, a friction
// force, the specimen's mass and a late load cell on what is read and not on what moves, bad parameters refused, and the stages as a study config builds
// them.
#include "core/rig_effects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "study/study.h"

namespace rths::core {
namespace {

TEST(Backlash, TheOutputMovesOnlyOnceThePlayIsTakenUp) {
  MotionLimit play = MotionLimit::backlash(0.002);           // 1 mm each way
  EXPECT_DOUBLE_EQ(play.step({0.001, 0.0008, 0.0}), 0.0);    // inside the play
  EXPECT_DOUBLE_EQ(play.step({0.002, 0.003, 0.0}), 0.002);   // dragged at the far edge
  EXPECT_DOUBLE_EQ(play.step({0.003, 0.0025, 0.0}), 0.002);  // reversal: the play again
  EXPECT_DOUBLE_EQ(play.step({0.004, 0.0, 0.0}), 0.001);     // dragged back
  play.reset();
  EXPECT_DOUBLE_EQ(play.step({0.001, 0.0005, 0.0}), 0.0);
  EXPECT_THROW(MotionLimit::backlash(-1e-3), std::invalid_argument);
  EXPECT_THROW(MotionLimit::backlash(std::nan("")), std::invalid_argument);
}

TEST(VelocityLimit, TheOutputMovesAtMostTheLimitTimesTheStep) {
  MotionLimit valve = MotionLimit::velocity_limit(0.05, 0.01);  // 0.5 mm per step
  EXPECT_DOUBLE_EQ(valve.step({0.01, 0.002, 0.0}), 0.0005);
  EXPECT_DOUBLE_EQ(valve.step({0.02, 0.002, 0.0}), 0.001);
  EXPECT_DOUBLE_EQ(valve.step({0.03, 0.0012, 0.0}), 0.0012);  // within reach: followed
  EXPECT_DOUBLE_EQ(valve.step({0.04, -0.01, 0.0}), 0.0007);
  EXPECT_THROW(MotionLimit::velocity_limit(0.0, 0.01), std::invalid_argument);
  EXPECT_THROW(MotionLimit::velocity_limit(0.05, 0.0), std::invalid_argument);
  // Linear analysis leaves the limit out and says so.
  EXPECT_EQ(valve.linearity().kind, Linearity::Kind::kLinearised);
  EXPECT_DOUBLE_EQ(std::abs(valve.frequency_response(10.0)), 1.0);
}

TEST(StrokeLimit, TheOutputStopsAtEitherEndOfTheStroke) {
  MotionLimit rod = MotionLimit::stroke_limit(0.01);  // +-10 mm
  EXPECT_DOUBLE_EQ(rod.step({0.001, 0.004, 0.0}), 0.004);
  EXPECT_DOUBLE_EQ(rod.step({0.002, 0.013, 0.0}), 0.01);
  EXPECT_DOUBLE_EQ(rod.step({0.003, -0.02, 0.0}), -0.01);  // from one end to the other in a step
  EXPECT_DOUBLE_EQ(rod.step({0.004, 0.009, 0.0}), 0.009);
  EXPECT_THROW(MotionLimit::stroke_limit(0.0), std::invalid_argument);
  EXPECT_THROW(MotionLimit::stroke_limit(std::nan("")), std::invalid_argument);
  EXPECT_EQ(rod.linearity().kind, Linearity::Kind::kLinearised);
  EXPECT_NE(rod.describe().find("10 mm"), std::string::npos) << rod.describe();
}

// A displacement sensor reading 5 % high: the read is off by 5 % of what the stage passed, the
// force and the motion are not.
TEST(SensorDrift, AScaledDisplacementSensorReadsOffByItsScaleOfTheDisplacement) {
  SensorErrors errors;
  errors.displacement_scale = 1.05;
  errors.displacement_offset = 0.001;
  DelayChain chain;
  chain.add(std::make_unique<MotionLimit>(MotionLimit::stroke_limit(0.02)));
  chain.add(std::make_unique<SensorDrift>(errors));
  EXPECT_DOUBLE_EQ(chain.step({0.001, 0.01, 0.0}), 0.01);
  EXPECT_DOUBLE_EQ(chain.measured(), 1.05 * 0.01 + 0.001);
  EXPECT_DOUBLE_EQ(chain.measure_force(300.0), 300.0);
  errors.displacement_scale = 0.0;
  EXPECT_THROW(SensorDrift{errors}, std::invalid_argument);
}

TEST(SensorDrift, TheSensorsReadOffTheTruthAndTheSpecimenIsNotMoved) {
  SensorDrift sensors({0.001, 0.0002, 50.0, -4.0});
  EXPECT_DOUBLE_EQ(sensors.step({2.0, 0.01, 0.0}), 0.01);
  EXPECT_DOUBLE_EQ(sensors.sensor_error(), 0.001 + 0.0002 * 2.0);
  EXPECT_DOUBLE_EQ(sensors.measure_force(1000.0), 1000.0 + 50.0 - 4.0 * 2.0);
  DelayChain chain;
  chain.add(sensors.clone());
  EXPECT_DOUBLE_EQ(chain.step({2.0, 0.01, 0.0}), 0.01);
  EXPECT_DOUBLE_EQ(chain.measured(), 0.01 + 0.001 + 0.0004);
  EXPECT_THROW(SensorDrift({std::nan(""), 0.0, 0.0, 0.0}), std::invalid_argument);
}

TEST(ViscousForce, TheLoadCellReadsDampingTimesTheRateAndTheSpecimenIsNotMoved) {
  ViscousForce damper(2000.0, 0.001);
  EXPECT_DOUBLE_EQ(damper.step({0.001, 0.0001, 0.0}), 0.0001);
  EXPECT_DOUBLE_EQ(damper.measure_force(500.0), 500.0 + 2000.0 * 0.1);  // 0.1 m/s
  EXPECT_DOUBLE_EQ(damper.step({0.002, 0.0001, 0.0}), 0.0001);
  EXPECT_DOUBLE_EQ(damper.measure_force(500.0), 500.0);  // at rest
  DelayChain chain;
  chain.add(std::make_unique<MotionLimit>(MotionLimit::backlash(0.0)));
  chain.add(damper.clone());
  chain.reset();
  EXPECT_DOUBLE_EQ(chain.step({0.001, -0.0002, 0.0}), -0.0002);
  EXPECT_DOUBLE_EQ(chain.measure_force(0.0), 2000.0 * -0.2);
  EXPECT_DOUBLE_EQ(chain.measured(), -0.0002);
  EXPECT_THROW(ViscousForce(-1.0, 0.001), std::invalid_argument);
  EXPECT_THROW(ViscousForce(std::nan(""), 0.001), std::invalid_argument);
}

TEST(InertiaForce, TheLoadCellReadsMassTimesTheAccelerationAtItsOwnStep) {
  // From rest, u = t^2 (2 m/s^2): from the third step on, the four samples the backward difference
  // takes lie on the parabola, and the load cell reads 50 kg x 2 m/s^2 on top of the spring.
  InertiaForce mass(50.0, 0.001);
  for (int k = 1; k <= 6; ++k) {
    const double t = 0.001 * k;
    EXPECT_DOUBLE_EQ(mass.step({t, t * t, 0.0}), t * t);  // the specimen is not moved
    const double read = mass.measure_force(500.0);
    if (k >= 3) EXPECT_NEAR(read, 500.0 + 50.0 * 2.0, 1e-6) << "step " << k;
  }
  // A constant rate: no acceleration once the samples are on the line.
  InertiaForce steady(50.0, 0.001);
  for (int k = 1; k <= 5; ++k) {
    steady.step({0.001 * k, 1e-4 * k, 0.0});
    if (k >= 3) EXPECT_NEAR(steady.measure_force(7.0), 7.0, 1e-6) << "step " << k;
  }
  mass.reset();
  mass.step({0.001, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(mass.measure_force(7.0), 7.0);
  EXPECT_THROW(InertiaForce(-1.0, 0.001), std::invalid_argument);
  EXPECT_THROW(InertiaForce(std::nan(""), 0.001), std::invalid_argument);
  EXPECT_THROW(InertiaForce(1.0, 0.0), std::invalid_argument);
}

TEST(FrictionForce, TheLoadCellReadsASmoothedCoulombForceAgainstTheRateAtItsOwnStep) {
  // From rest, u = 0.25 t^2 (a rate of t / 2 m/s): from the second step on, the three samples
  // the backward difference takes lie on the parabola, so it reads the rate at the step itself.
  FrictionForce friction(200.0, 0.001, 0.001);
  for (int k = 1; k <= 4; ++k) {
    const double t = 0.001 * k;
    EXPECT_DOUBLE_EQ(friction.step({t, 0.25 * t * t, 0.0}), 0.25 * t * t);
    const double read = friction.measure_force(500.0);
    if (k >= 2) EXPECT_NEAR(read, 500.0 + 200.0 * std::tanh(0.5 * t / 0.001), 1e-6) << "step " << k;
  }
  FrictionForce still(200.0, 0.001, 0.001);
  for (int k = 1; k <= 3; ++k) {
    still.step({0.001 * k, 0.002, 0.0});  // a step of 2 mm at the first step, then at rest
    if (k >= 3) EXPECT_DOUBLE_EQ(still.measure_force(3.0), 3.0);
  }
  still.reset();
  still.step({0.001, -0.0001, 0.0});  // -0.15 m/s from rest: full friction against it
  EXPECT_NEAR(still.measure_force(0.0), -200.0, 1e-6);
  EXPECT_THROW(FrictionForce(-1.0, 0.001, 0.001), std::invalid_argument);
  try {
    FrictionForce(1.0, 0.0, 0.001);
    FAIL() << "a smoothing velocity of 0 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("smoothing_velocity"), std::string::npos) << e.what();
  }
}

TEST(ForceDelay, TheIntegratorReceivesTheForceReadDelaySecondsBefore) {
  ForceDelay late(0.0015, 0.001);  // a step and a half
  std::vector<double> received;
  for (int k = 1; k <= 5; ++k) {
    EXPECT_DOUBLE_EQ(late.step({0.001 * k, 0.0003, 0.0}), 0.0003);  // the motion is not late
    received.push_back(late.measure_force(100.0 * k));
  }
  // Before the first step's force: the first's; then 1.5 steps back, interpolated.
  EXPECT_DOUBLE_EQ(received[0], 100.0);
  EXPECT_DOUBLE_EQ(received[1], 100.0);
  EXPECT_NEAR(received[2], 150.0, 1e-9);
  EXPECT_NEAR(received[3], 250.0, 1e-9);
  EXPECT_NEAR(received[4], 350.0, 1e-9);
  ForceDelay none(0.0, 0.001);
  none.step({0.001, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(none.measure_force(42.0), 42.0);
  EXPECT_DOUBLE_EQ(late.nominal_delay(), 0.0);  // the displacement's lag
  EXPECT_THROW(ForceDelay(-0.001, 0.001), std::invalid_argument);
}

TEST(RigEffects, AStudyBuildsThemAndRefusesBadValuesNamingTheField) {
  config::DelayStage stage;
  stage.mutable_velocity_limit()->set_max_velocity(0.05);
  stage.set_amplitude_gain(1.1);
  const auto valve = study::make_delay_stage(stage, 0.01, ".");
  EXPECT_DOUBLE_EQ(valve->step({0.01, 0.002, 0.0}), 1.1 * 0.0005);
  const std::string bad =
      "structure { sdof { period: 0.5 } } cases { name: \"c\" delay { velocity_limit {} } }";
  try {
    (void)study::parse_study(bad, "bad.textproto");
    FAIL() << "a velocity limit of 0 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("velocity_limit.max_velocity"), std::string::npos)
        << e.what();
  }
  config::DelayStage rod;
  rod.mutable_stroke_limit()->set_stroke(0.01);
  EXPECT_DOUBLE_EQ(study::make_delay_stage(rod, 0.01, ".")->step({0.01, 0.02, 0.0}), 0.01);
  config::DelayStage sensors;
  sensors.mutable_sensor_drift()->set_displacement_scale(1.1);
  DelayChain read;
  read.add(study::make_delay_stage(sensors, 0.01, "."));
  read.step({0.01, 0.002, 0.0});
  EXPECT_DOUBLE_EQ(read.measured(), 1.1 * 0.002);
  for (const auto& [text, field] :
       {std::pair{"stroke_limit { stroke: 0 }", "stroke_limit.stroke"},
        std::pair{"sensor_drift { displacement_scale: -1 }", "sensor_drift.displacement_scale"}}) {
    try {
      (void)study::parse_study(std::string("structure { sdof { period: 0.5 } } cases { name: \"c\" "
                                           "delay { ") +
                                   text + " } }",
                               "bad.textproto");
      FAIL() << text << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
  for (const auto& [text, field] :
       {std::pair{"inertia_force { mass: -1 }", "inertia_force.mass"},
        std::pair{"friction_force { friction_force: 100 }", "friction_force.smoothing_velocity"},
        std::pair{"friction_force { friction_force: -1 smoothing_velocity: 0.001 }",
                  "friction_force.friction_force"},
        std::pair{"force_delay { delay: 2 }", "force_delay.delay"}}) {
    try {
      (void)study::parse_study(std::string("structure { sdof { period: 0.5 } } cases { name: \"c\" "
                                           "delay { ") +
                                   text + " } }",
                               "bad.textproto");
      FAIL() << text << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
  config::DelayStage mass, friction, late;
  mass.mutable_inertia_force()->set_mass(10.0);
  friction.mutable_friction_force()->set_friction_force(100.0);
  friction.mutable_friction_force()->set_smoothing_velocity(0.002);
  late.mutable_force_delay()->set_delay(0.003);
  DelayChain rig;
  for (const auto* stage : {&mass, &friction, &late})
    rig.add(study::make_delay_stage(*stage, 0.001, "."));
  EXPECT_NE(rig.describe().find("inertia_force(10 kg)"), std::string::npos) << rig.describe();
  EXPECT_NE(rig.describe().find("friction_force(100 N"), std::string::npos) << rig.describe();
  EXPECT_NE(rig.describe().find("force_delay(3 ms)"), std::string::npos) << rig.describe();
  try {
    (void)study::parse_study(
        "structure { sdof { period: 0.5 } } cases { name: \"c\" delay { "
        "viscous_force { damping: -5 } } }",
        "bad.textproto");
    FAIL() << "a negative damping was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("viscous_force.damping"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rths::core
