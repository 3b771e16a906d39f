#include "identify/lab/generator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/metrics.h"

namespace rths::identify {
namespace {

TEST(GeneratorTest, ChirpCommandHasTheAmplitudeAndTheDelayShows) {
  GeneratorSpec spec;
  spec.delay = 0.02;
  spec.displacement_noise = 0.0;
  const MeasuredData d = generate_measured(spec);
  EXPECT_NEAR(core::peak_abs(d.command), spec.amplitude, 1e-5);
  EXPECT_NEAR(core::j1_delay(d.command, d.measured, d.dt, 0.1), 0.02, 0.001);
}

TEST(GeneratorTest, EarthquakeLikeCommandIsSeededAndScaled) {
  GeneratorSpec spec;
  spec.command = GeneratorSpec::Command::kEarthquake;
  const MeasuredData a = generate_measured(spec), b = generate_measured(spec);
  EXPECT_EQ(a.command, b.command);
  EXPECT_EQ(a.force, b.force);
  EXPECT_NEAR(core::peak_abs(a.command), spec.amplitude, 1e-12);
  spec.seed = 2;
  EXPECT_NE(generate_measured(spec).command, a.command);
}

TEST(GeneratorTest, SpecimenEffectsAppearInTheForce) {
  GeneratorSpec spec;
  spec.displacement_noise = 0.0;
  spec.force_noise = 0.0;
  spec.delay = 0.0;
  const MeasuredData linear = generate_measured(spec);
  for (std::size_t i = 0; i < linear.size(); i += 500) {
    EXPECT_NEAR(linear.force[i], spec.stiffness * linear.measured[i], 1e-9);
  }
  spec.force_offset = 50.0;
  spec.coulomb_force = 20.0;
  const MeasuredData with_friction = generate_measured(spec);
  double max_extra = 0.0;
  for (std::size_t i = 0; i < linear.size(); ++i) {
    max_extra = std::max(max_extra, with_friction.force[i] - linear.force[i]);
  }
  EXPECT_NEAR(max_extra, 70.0, 1.0);
}

TEST(GeneratorTest, ActuatorOffsetAndBacklash) {
  GeneratorSpec spec;
  spec.displacement_noise = 0.0;
  spec.offset = 1e-4;
  spec.backlash_width = 4e-4;
  const MeasuredData d = generate_measured(spec);
  const double peak = *std::max_element(d.measured.begin(), d.measured.end());
  EXPECT_NEAR(peak, spec.amplitude - 2e-4 + 1e-4, 2e-5);
}

TEST(GeneratorTest, BadSpecsAreRejected) {
  GeneratorSpec spec;
  spec.duration = 0.1;
  EXPECT_THROW(generate_measured(spec), std::invalid_argument);
  spec = {};
  spec.dt = -1;
  EXPECT_THROW(generate_measured(spec), std::invalid_argument);
}

}  // namespace
}  // namespace rths::identify
