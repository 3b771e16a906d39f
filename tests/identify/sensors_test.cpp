// What a run's record says of its sensors (identify/run/sensors.h): which part each effect is
// on, noise named only above what the header declares, and a displacement sensor's scale taken
// out of the actuator and the specimen in the models the re-run and the written study hold.
#include "identify/run/sensors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "identify/fit/effect_parameters.h"
#include "identify/run/run_config.h"
#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "tests/identify/independent_record.h"

namespace rths::identify {
namespace {

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

ActuatorPath identified_path(const std::string& name, const test::RigTruth& rig) {
  const RunIdentification run =
      identify_run_record(test::independent_record(name, rig, 8.0), IdentifyOptions{});
  return run.actuators.at(0);
}

TEST(Sensors, EachEffectIsOnItsPart) {
  EXPECT_EQ(part_of("offset_drift", Channel::kMeasured, 2), "displacement sensor 2");
  EXPECT_EQ(part_of("noise", Channel::kMeasured, 1), "displacement sensor 1");
  EXPECT_EQ(part_of("scale", Channel::kMeasured, 1), "displacement sensor 1");
  EXPECT_EQ(part_of("backlash", Channel::kMeasured, 1), "actuator 1");
  EXPECT_EQ(part_of("noise", Channel::kForce, 3), "load cell 3");
  EXPECT_EQ(part_of("offset_drift", Channel::kForce, 1), "load cell 1");
  EXPECT_EQ(part_of("stiffness change", Channel::kForce, 1), "specimen 1");
}

// The same noisy sensors, undeclared and then declared (a tracking loop's noise): named only
// when they are above what the header says.
TEST(Sensors, NoiseTheHeaderDeclaresIsNotNamed) {
  test::RigTruth rig;
  rig.displacement_noise = 1e-4;
  rig.force_noise = 10.0;
  ActuatorPath path = identified_path("sensors_noise", rig);
  ASSERT_TRUE(has(path.undeclared, "noise"));
  ASSERT_TRUE(has(path.specimen_undeclared, "noise"));
  EXPECT_NEAR(path.displacement_noise, 1e-4, 1e-5);
  EXPECT_NEAR(path.force_noise, 10.0, 1.0);
  path.undeclared.clear();
  path.specimen_undeclared.clear();
  path.declared_displacement_noise = 1e-4;
  path.declared_force_noise = 10.0;
  judge_sensors(path);
  EXPECT_FALSE(has(path.undeclared, "noise"));
  EXPECT_FALSE(has(path.specimen_undeclared, "noise"));
}

// A displacement sensor reading 10 % high: the models the re-run holds have the declared gain and
// no specimen of their own, and the written study reads the displacement through the scale.
TEST(Sensors, ADisplacementSensorsScaleLeavesTheActuatorAndTheSpecimenAsDeclared) {
  test::RigTruth rig;
  rig.displacement_scale = 1.1;
  const RunIdentification run =
      identify_run_record(test::independent_record("sensors_scale", rig, 8.0), IdentifyOptions{});
  const ActuatorPath& path = run.actuators.at(0);
  ASSERT_TRUE(has(path.undeclared, "scale")) << run_record_text(run);
  EXPECT_NEAR(path.displacement_scale, 1.1, 0.005);
  EXPECT_GT(path.displacement_scale_error, 0.0);
  const RigModels models = rig_models(path);
  const SignalScales scales = signal_scales(identified_signals(path.id, Channel::kMeasured));
  ASSERT_TRUE(models.actuator.has_value());
  EXPECT_NEAR(*models.actuator->param(std::nullopt, "gain", scales), 1.0, 0.005);
  EXPECT_FALSE(models.specimen.has_value());
  const IdentifiedRun written = identified_run(run, ".", ".");
  double read_scale = 0.0;
  for (const auto& c : written.study.cases())
    for (const auto& stage : c.delay())
      if (stage.has_sensor_drift()) read_scale = stage.sensor_drift().displacement_scale();
  EXPECT_NEAR(read_scale, 1.1, 0.005);
}

// A real actuator gain error with the declared specimen is not a sensor's scale: the force per
// command is off too.
TEST(Sensors, AnActuatorsGainErrorStaysOnTheActuator) {
  test::RigTruth rig;
  rig.gain = 1.1;
  const ActuatorPath path = identified_path("sensors_gain", rig);
  EXPECT_TRUE(has(path.undeclared, "gain error"));
  EXPECT_FALSE(has(path.undeclared, "scale"));
  EXPECT_DOUBLE_EQ(path.displacement_scale, 1.0);
}

}  // namespace
}  // namespace rths::identify
