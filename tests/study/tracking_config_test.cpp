#include "study/tracking_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <memory>
#include <string>

namespace rths::study {
namespace {

config::DelayStage::TrackingLoop first_order_loop(double kp, double ki) {
  config::DelayStage::TrackingLoop spec;
  spec.mutable_plant()->add_numerator(50.0);  // 50 / (s + 50): a 20 ms first-order plant
  spec.mutable_plant()->add_denominator(1.0);
  spec.mutable_plant()->add_denominator(50.0);
  spec.mutable_controller()->mutable_pid()->set_kp(kp);
  spec.mutable_controller()->mutable_pid()->set_ki(ki);
  return spec;
}

TEST(DiscreteFilterTest, TustinPiIsTrapezoidalIntegration) {
  config::DelayStage::LinearFilter spec;
  spec.mutable_pid()->set_kp(2.0);
  spec.mutable_pid()->set_ki(10.0);
  const double h = 0.01;
  core::DiscreteFilter pi = make_filter(spec, h, "c");
  // A unit step: y_k = kp + ki h (k + 1/2) (trapezoids of the held input, the first a half).
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(pi.step(1.0), 2.0 + 10.0 * h * (k + 0.5), 1e-12) << k;
  pi.reset();
  EXPECT_NEAR(pi.step(1.0), 2.0 + 10.0 * h * 0.5, 1e-12);
  EXPECT_EQ(core::DiscreteFilter().step(3.5), 3.5);
}

TEST(DiscreteFilterTest, PhaseLeadKeepsItsDcGainAndBadFiltersNameTheField) {
  config::DelayStage::LinearFilter spec;
  spec.mutable_phase_lead()->set_gain(50.8);
  spec.mutable_phase_lead()->set_zero(168.6);
  spec.mutable_phase_lead()->set_pole(8570);
  const core::DiscreteFilter lead = make_filter(spec, 1.0 / 4096, "feedforward");
  EXPECT_NEAR(std::abs(lead.response(1.0)), 50.8 * 168.6 / 8570, 1e-12);
  spec.mutable_phase_lead()->set_pole(0.0);
  try {
    make_filter(spec, 1.0 / 4096, "cases[1].feedforward");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cases[1].feedforward.phase_lead"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(make_filter(config::DelayStage::LinearFilter(), 0.001, "f"), std::invalid_argument);
}

// A state space is the transfer function it realises: the PI 2 + 95/s as x' = u, y = 95 x + 2 u
// (Tustin) steps as the named PI does; a discrete one x+ = x + u, y = 0.5 x + u is
// (1 - 0.5 z^-1) / (1 - z^-1); a wrong size names the field and the sizes.
TEST(DiscreteFilterTest, StateSpaceControllerIsTheTransferFunctionItRealises) {
  const double h = 1.0 / 4096;
  config::DelayStage::LinearFilter pi, space;
  pi.mutable_pid()->set_kp(2.0);
  pi.mutable_pid()->set_ki(95.0);
  auto* ss = space.mutable_state_space();
  ss->set_states(1);
  ss->add_a(0.0);
  ss->add_b(1.0);
  ss->add_c(95.0);
  ss->set_d(2.0);
  core::DiscreteFilter named = make_filter(pi, h, "c"), realised = make_filter(space, h, "c");
  for (int k = 0; k < 50; ++k) {
    const double u = std::sin(0.3 * k);
    EXPECT_NEAR(realised.step(u), named.step(u), 1e-12) << k;
  }

  // Two states with a coupling: x' = [0 1; -4 -0.4] x + [0; 1] u, y = [4 0] x: 4 / (s^2 + 0.4 s +
  // 4).
  config::DelayStage::LinearFilter oscillator, continuous;
  auto* two = oscillator.mutable_state_space();
  two->set_states(2);
  for (double v : {0.0, 1.0, -4.0, -0.4}) two->add_a(v);
  for (double v : {0.0, 1.0}) two->add_b(v);
  for (double v : {4.0, 0.0}) two->add_c(v);
  for (double v : {4.0}) continuous.mutable_continuous()->add_numerator(v);
  for (double v : {1.0, 0.4, 4.0}) continuous.mutable_continuous()->add_denominator(v);
  const core::DiscreteFilter from_space = make_filter(oscillator, 0.01, "c"),
                             from_tf = make_filter(continuous, 0.01, "c");
  for (double w : {0.5, 2.0, 20.0}) {
    const std::complex<double> z = std::exp(std::complex<double>(0.0, w * 0.01));
    EXPECT_NEAR(std::abs(from_space.response(z) - from_tf.response(z)), 0.0, 1e-12) << w;
  }

  ss->set_discrete(true);
  ss->set_c(0, 0.5);
  ss->set_d(1.0);
  ss->set_a(0, 1.0);
  core::DiscreteFilter discrete = make_filter(space, h, "c"), expected({1.0, -0.5}, {1.0, -1.0});
  for (int k = 0; k < 20; ++k) EXPECT_NEAR(discrete.step(1.0), expected.step(1.0), 1e-12) << k;

  ss->add_b(1.0);
  try {
    make_filter(space, h, "cases[1].delay[0].tracking_loop.controller");
    FAIL() << "a 1-state space with 2 inputs in b was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "tracking_loop.controller.state_space: a needs states^2 = 1 values"),
              std::string::npos)
        << e.what();
  }
}

TEST(ZohPlantTest, FirstOrderStepIsExactAtTheSamples) {
  const double h = 0.002;
  core::ZohPlant plant({50.0}, {1.0, 50.0}, h);
  for (int k = 1; k <= 20; ++k) {
    plant.advance(1.0);
    EXPECT_NEAR(plant.output(), 1.0 - std::exp(-50.0 * h * k), 1e-12) << k;
  }
  EXPECT_NEAR(std::abs(plant.response(1.0)), 1.0, 1e-12);  // DC gain
  EXPECT_THROW(core::ZohPlant({1.0, 0.0}, {1.0, 50.0}, h),
               std::invalid_argument);  // not strictly proper
}

// The benchmark plant's companion form spans twelve decades; its discretisation must still settle
// at the DC gain for any draw of the perturbed plants (here beta2 2 % off nominal).
TEST(ZohPlantTest, BenchmarkPlantSettlesAtItsDcGainWhenPerturbed) {
  config::DelayStage::BenchmarkPlant spec;
  spec.set_beta2(1.02e5);
  const core::ContinuousTransferFunction tf =
      core::benchmark_actuator_transfer_function(benchmark_plant_parameters(spec));
  core::ZohPlant plant(tf.numerator, tf.denominator, 1.0 / 4096);
  for (int k = 0; k < 3 * 4096; ++k) plant.advance(1.0);
  EXPECT_NEAR(plant.output(), tf.numerator.back() / tf.denominator.back(), 1e-3);
}

TEST(ConverterTest, SaturatesAndQuantises) {
  const core::Converter c{3.8, 0.25};
  EXPECT_EQ(c.analog_to_digital(0.3), 0.25);
  EXPECT_EQ(c.analog_to_digital(-9.0), -3.75);  // saturated at -3.8, then quantised
  EXPECT_EQ(c.digital_to_analog(9.0), 3.8);     // quantised, then saturated
  EXPECT_EQ(core::Converter{}.analog_to_digital(0.123), 0.123);
}

TEST(TrackingLoopTest, PiAroundAFirstOrderPlantTracksWithItsLoopsLag) {
  const double h = 0.001;
  core::TrackingLoop loop = make_tracking_loop(first_order_loop(2.0, 100.0), h, "tracking_loop");
  // Closed loop ~ unity at DC; the lag at low frequency is positive and of a few ms.
  EXPECT_NEAR(std::abs(loop.response(0.1)), 1.0, 1e-6);
  EXPECT_GT(loop.nominal_delay(), 0.001);
  EXPECT_LT(loop.nominal_delay(), 0.05);
  double x = 0.0;
  for (int k = 0; k < 2000; ++k) x = loop.step({k * h, 0.01, 0.0});
  EXPECT_NEAR(x, 0.01, 1e-6);  // the integrator removes the steady error
  // A ramp r = t: the output trails it by about the nominal delay.
  loop.reset();
  for (int k = 0; k < 3000; ++k) x = loop.step({k * h, k * h, 1.0});
  EXPECT_NEAR(2999 * h - x, loop.nominal_delay(), 2 * h);
}

TEST(TrackingLoopTest, SeededNoiseRepeatsAfterResetAndInACopy) {
  auto spec = first_order_loop(2.0, 100.0);
  spec.set_displacement_noise_rms(1e-4);
  spec.set_seed(7);
  core::TrackingLoop a = make_tracking_loop(spec, 0.001, "t");
  std::vector<double> first;
  for (int k = 0; k < 50; ++k) first.push_back(a.step({k * 0.001, 0.0, 0.0}));
  EXPECT_NE(first.back(), 0.0);  // the noise moved the plant through the controller
  a.reset();
  auto copy = a.clone();
  for (int k = 0; k < 50; ++k) {
    EXPECT_EQ(a.step({k * 0.001, 0.0, 0.0}), first[static_cast<std::size_t>(k)]);
    EXPECT_EQ(copy->step({k * 0.001, 0.0, 0.0}), first[static_cast<std::size_t>(k)]);
  }
}

// The displacement sensor's reading is the output plus the drawn error; the load cell's reading
// reaches the integrator force_delay_periods periods later, with its own noise.
TEST(TrackingLoopTest, SensorsReportTheirReadingsAndTheLoadCellItsDelayedForce) {
  auto spec = first_order_loop(2.0, 100.0);
  spec.set_force_delay_periods(2);
  core::TrackingLoop quiet = make_tracking_loop(spec, 0.001, "t");
  EXPECT_EQ(quiet.measure_force(10.0), 0.0);
  EXPECT_EQ(quiet.measure_force(20.0), 0.0);
  EXPECT_EQ(quiet.measure_force(30.0), 10.0);
  EXPECT_EQ(quiet.measure_force(40.0), 20.0);
  quiet.reset();
  EXPECT_EQ(quiet.measure_force(50.0), 0.0);  // reset empties the queue
  quiet.step({0.0, 0.01, 0.0});
  EXPECT_EQ(quiet.sensor_error(), 0.0);

  spec.set_force_delay_periods(0);
  spec.set_displacement_noise_rms(1e-4);
  spec.set_force_noise_rms(2.0);
  spec.set_seed(11);
  core::TrackingLoop noisy = make_tracking_loop(spec, 0.001, "t");
  double displacement_square = 0.0, force_square = 0.0;
  constexpr int kDraws = 20000;
  for (int k = 0; k < kDraws; ++k) {
    noisy.step({k * 0.001, 0.0, 0.0});
    displacement_square += noisy.sensor_error() * noisy.sensor_error();
    const double force_error = noisy.measure_force(5.0) - 5.0;
    force_square += force_error * force_error;
  }
  EXPECT_NEAR(std::sqrt(displacement_square / kDraws), 1e-4, 3e-6);
  EXPECT_NEAR(std::sqrt(force_square / kDraws), 2.0, 0.06);

  spec.set_force_delay_periods(65);
  try {
    core::TrackingLoop bad = make_tracking_loop(spec, 0.001, "cases[1].delay[0].tracking_loop");
    FAIL() << "a force delay of 65 periods was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "cases[1].delay[0].tracking_loop.force_delay_periods: 65 is outside 0..64"),
              std::string::npos)
        << e.what();
  }
  spec.set_force_delay_periods(0);
  spec.set_force_noise_rms(-1.0);
  EXPECT_THROW(make_tracking_loop(spec, 0.001, "t"), std::invalid_argument);
}

// A chain reports the specimen's displacement from step() and the sensor's reading from measured().
TEST(TrackingLoopTest, ChainMeasuresWhatItsSensorReads) {
  auto spec = first_order_loop(2.0, 100.0);
  spec.set_displacement_noise_rms(1e-3);
  spec.set_seed(3);
  core::DelayChain chain;
  chain.add(std::make_unique<core::TrackingLoop>(make_tracking_loop(spec, 0.001, "t")));
  core::TrackingLoop alone = make_tracking_loop(spec, 0.001, "t");
  for (int k = 0; k < 20; ++k) {
    const double output = chain.step({k * 0.001, 0.01, 0.0});
    EXPECT_EQ(output, alone.step({k * 0.001, 0.01, 0.0}));
    EXPECT_EQ(chain.measured(), output + alone.sensor_error());
  }
  EXPECT_NE(alone.sensor_error(), 0.0);
}

TEST(TrackingLoopTest, BenchmarkPlantIsTheNominalF1PlantUnlessOverridden) {
  const core::BenchmarkPlantParameters p = benchmark_plant_parameters({});
  EXPECT_EQ(p.a1_beta0, 2.1283e13);
  EXPECT_EQ(p.beta2, 9.9976e4);
  EXPECT_EQ(p.gain, 1.0261);
  EXPECT_NEAR(p.damping, 2 * 0.0097 * std::sqrt(1.19e6 * 29.13), 1e-12);
  config::DelayStage::BenchmarkPlant spec;
  spec.set_a3(4.0);
  EXPECT_EQ(benchmark_plant_parameters(spec).a3, 4.0);
  // Its DC gain: gain a1b0 / (beta2 a3 k + a1b0).
  const core::ContinuousTransferFunction tf = core::benchmark_actuator_transfer_function(p);
  EXPECT_NEAR(tf.numerator[0] / tf.denominator.back(),
              1.0261 * 2.1283e13 / (9.9976e4 * 3.3 * 1.19e6 + 2.1283e13), 1e-12);
  config::DelayStage::TrackingLoop loop;
  EXPECT_THROW(make_tracking_loop(loop, 1.0 / 4096, "t"), std::invalid_argument);  // no plant
}

TEST(TrackingLoopTest, AnExplicitZeroMassOrStiffnessIsRefusedNotRunAsTheNominal) {
  config::DelayStage::BenchmarkPlant spec;
  spec.set_mass(0);
  try {
    benchmark_plant_parameters(spec);
    FAIL() << "mass 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("benchmark_plant.mass"), std::string::npos) << e.what();
  }
  spec.clear_mass();
  spec.set_stiffness(-1);
  EXPECT_THROW(benchmark_plant_parameters(spec), std::invalid_argument);
  spec.set_stiffness(2e6);
  spec.set_mass(40);
  EXPECT_EQ(benchmark_plant_parameters(spec).mass, 40);
  EXPECT_EQ(benchmark_plant_parameters(spec).stiffness, 2e6);
}

}  // namespace
}  // namespace rths::study
