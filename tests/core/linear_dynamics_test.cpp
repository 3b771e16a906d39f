#include "core/linear_dynamics.h"
#include "study/tracking_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <memory>
#include <numbers>
#include <string>

#include "core/compensation.h"
#include "core/delay.h"
#include "core/tracking.h"

namespace rths::core {
namespace {

using cd = std::complex<double>;
constexpr double kDt = 0.001;

cd z_at(double omega, double dt) { return std::exp(cd(0.0, omega * dt)); }

// The realisation's discrete response at z = e^{i w dt}.
cd realised(const LinearDynamics& block, double omega, double dt = kDt) {
  return response_at(block.state_space(), z_at(omega, dt));
}

// Tustin maps s = (2 / dt) (z - 1) / (z + 1): on the unit circle, w_c = (2 / dt) tan(w dt / 2).
double warped(double omega, double dt = kDt) { return 2.0 / dt * std::tan(omega * dt / 2.0); }

void expect_near(cd actual, cd expected, double tolerance, const std::string& what) {
  EXPECT_NEAR(std::abs(actual - expected), 0.0, tolerance)
      << what << ": " << actual << " vs " << expected;
}

TEST(LinearBlocks, SeriesIsTheProductOfTheResponsesAndResponseAtReadsTheRealisation) {
  const LinearBlock delay2 = fir_block(0.0, {0.0, 1.0});               // z^-2
  const LinearBlock lag = direct_form_block({0.5, 0.0}, {1.0, -0.5});  // 0.5 / (1 - 0.5 z^-1)
  for (double w : {1.0, 300.0, 2500.0}) {
    const cd z = z_at(w, kDt);
    expect_near(response_at(delay2, z), 1.0 / (z * z), 1e-12, "z^-2");
    expect_near(response_at(lag, z), 0.5 / (1.0 - 0.5 / z), 1e-12, "lag");
    expect_near(response_at(series(lag, delay2), z), 0.5 / (1.0 - 0.5 / z) / (z * z), 1e-12,
                "series");
    expect_near(response_at(series(gain_block(3.0), lag), z), 1.5 / (1.0 - 0.5 / z), 1e-12, "gain");
  }
  // 2.5 steps: half of u[k-2], half of u[k-3].
  const cd z = z_at(700.0, kDt);
  expect_near(response_at(shift_block(0.0025, kDt), z), 0.5 / (z * z) + 0.5 / (z * z * z), 1e-12,
              "fractional shift");
  EXPECT_THROW(shift_block(-0.001, kDt), std::invalid_argument);
}

TEST(LinearBlocks, PlantModelFoldsGainsDelaysAndPolynomials) {
  PlantModel g;
  g.append({1.0}, {0.01, 1.0});
  PlantModel shift;
  shift.delay = 0.003;
  shift.gain = 2.0;
  g.append(shift);
  const double w = 100.0;
  expect_near(g.at(w), 2.0 * std::exp(cd(0.0, -0.3)) / cd(1.0, 1.0), 1e-12, "2 e^{-0.3i}/(1+i)");
  EXPECT_EQ(g.describe(), "plant(delay 3 ms, gain 2, order 1/0)");
}

// Each delay stage: H by hand, and its realisation's response at z = e^{i w dt} (exact where
// the realisation is exact: whole-step shifts, Tustin at the warped frequency).
TEST(DelayStageDynamics, ShiftIsEToTheMinusIOmegaTauAndItsRegister) {
  TimeShift shift(0.003, kDt);
  shift.set_gain(1.5);
  EXPECT_EQ(shift.linearity().kind, Linearity::Kind::kTimeInvariant);
  for (double w : {10.0, 450.0, 3000.0}) {
    expect_near(shift.frequency_response(w), 1.5 * std::exp(cd(0.0, -0.003 * w)), 1e-12, "H");
    expect_near(realised(shift, w), shift.frequency_response(w), 1e-12, "register");
  }
  EXPECT_EQ(shift.transfer_function()->delay, 0.003);
  EXPECT_EQ(shift.transfer_function()->gain, 1.5);
}

TEST(DelayStageDynamics, FirstOrderIsOneOverOnePlusIOmegaTAndItsExactDiscretisation) {
  const double t = 0.01;
  FirstOrderActuator lag(t, kDt);
  expect_near(lag.frequency_response(100.0), cd(0.5, -0.5), 1e-12, "1 / (1 + i)");
  // The held-input recursion y = e y1 + (1 - e) u: (1 - e) z / (z - e), e = e^{-dt/T}.
  const double e = std::exp(-kDt / t);
  for (double w : {1.0, 100.0, 2000.0}) {
    const cd z = z_at(w, kDt);
    expect_near(realised(lag, w), (1.0 - e) * z / (z - e), 1e-12, "recursion");
  }
  // At low frequency the two agree to O(w dt).
  expect_near(realised(lag, 5.0), lag.frequency_response(5.0), 5.0 * kDt, "low frequency");
}

TEST(DelayStageDynamics, TransferFunctionIsNOverDAndItsTustinFilterAtTheWarpedFrequency) {
  // 2nd order: w_n = 200 rad/s, zeta = 0.3.
  TransferFunctionStage stage({4e4}, {1.0, 120.0, 4e4}, kDt);
  stage.set_gain(0.9);
  const double w = 200.0;
  expect_near(stage.frequency_response(w), 0.9 * 4e4 / cd(0.0, 120.0 * w), 1e-12,
              "at w_n: -i / (2 zeta)");
  for (double w_d : {5.0, 200.0, 1500.0}) {
    expect_near(realised(stage, w_d), stage.frequency_response(warped(w_d)), 1e-10, "Tustin");
  }
  // The benchmark's 5th-order plant (coefficients over 13 decades): its realisation's resolvent
  // is ill-conditioned, so agreement is to 1e-6.
  const TransferFunctionStage benchmark = *make_benchmark_actuator(kDt / 4);
  for (double w_d : {10.0, 150.0})
    expect_near(realised(benchmark, w_d, kDt / 4),
                benchmark.frequency_response(warped(w_d, kDt / 4)), 1e-6, "benchmark");
}

TEST(DelayStageDynamics, VelocityReadingAndTimeVaryingStagesAreNotRepresentable) {
  const Eq1Lead lead(0.01);
  const JitterShift jitter(0.005, 0.001, 1, kDt);
  EXPECT_EQ(lead.linearity().kind, Linearity::Kind::kNone);
  EXPECT_NE(lead.linearity().note.find("velocity"), std::string::npos);
  EXPECT_EQ(jitter.linearity().kind, Linearity::Kind::kNone);
  EXPECT_NE(jitter.linearity().note.find("redrawn"), std::string::npos);
  EXPECT_THROW(jitter.state_space(), std::invalid_argument);
  EXPECT_THROW(lead.frequency_response(1.0), std::invalid_argument);
  EXPECT_FALSE(jitter.transfer_function().has_value());
}

// Unity feedback around the held 50 / (s + 50): P(z) = (1 - p) / (z - p), p = e^{-50 h}, so
// H = P / (1 + P) = (1 - p) / (z - 2p + 1), then the load cell's d periods z^-d.
TEST(DelayStageDynamics, TrackingLoopIsItsClosedLoopThenTheForceDelay) {
  const double h = 1.0 / 1024;
  config::DelayStage::TrackingLoop spec;
  spec.mutable_plant()->add_numerator(50.0);
  spec.mutable_plant()->add_denominator(1.0);
  spec.mutable_plant()->add_denominator(50.0);
  spec.set_force_delay_periods(2);
  const TrackingLoop unity = study::make_tracking_loop(spec, h, "loop");
  const double p = std::exp(-50.0 * h);
  for (double w : {3.0, 300.0, 2500.0}) {
    const cd z = z_at(w, h);
    const cd expected = (1.0 - p) / (z - 2.0 * p + 1.0) / (z * z);
    expect_near(unity.frequency_response(w), expected, 1e-12, "hand");
    expect_near(realised(unity, w, h), expected, 1e-12, "realisation");
  }
  EXPECT_EQ(unity.linearity().kind, Linearity::Kind::kTimeInvariant);
  // A PI and a phase-lead feedforward: the realisation is the response the loop states.
  spec.mutable_controller()->mutable_pid()->set_kp(2.0);
  spec.mutable_controller()->mutable_pid()->set_ki(95.0);
  auto* lead = spec.mutable_feedforward()->mutable_phase_lead();
  lead->set_gain(5.0);
  lead->set_zero(100.0);
  lead->set_pole(500.0);
  spec.mutable_converter()->set_quantum(1e-6);
  const TrackingLoop pi = study::make_tracking_loop(spec, h, "loop");
  for (double w : {3.0, 300.0, 2500.0})
    expect_near(realised(pi, w, h), pi.frequency_response(w), 1e-10, "PI loop");
  EXPECT_EQ(pi.linearity().kind, Linearity::Kind::kLinearised);
  EXPECT_NE(pi.linearity().note.find("converters"), std::string::npos);
}

// Each compensator: H by hand, and its realisation.
TEST(CompensatorDynamics, PolynomialIsItsWeightsOnDelaysSpacedHApart) {
  // Order 1, lead L, spacing 2 steps: c0 = 1 + L/h, c1 = -L/h, H = c0 + c1 e^{-i w h}.
  const double lead = 0.003, h = 2 * kDt;
  const PolynomialExtrapolation p(1, lead, 2, kDt);
  for (double w : {10.0, 400.0, 2000.0}) {
    const cd expected = (1.0 + lead / h) - lead / h * std::exp(cd(0.0, -w * h));
    expect_near(p.frequency_response(w), expected, 1e-12, "hand");
    expect_near(realised(p, w), expected, 1e-12, "register");
  }
  EXPECT_EQ(p.linearity().kind, Linearity::Kind::kTimeInvariant);
}

TEST(CompensatorDynamics, AtsIsA0PlusA1IOmegaMinusA2OmegaSquaredFrozenAndSaysSo) {
  AtsParameters a;
  a.a0 = 1.1;
  a.a1 = 0.01;
  a.a2 = 1e-4;
  a.a2_bounds = {-1e-3, 1e-3};
  const AdaptiveTimeSeries ats(a, kDt);
  expect_near(ats.frequency_response(10.0), cd(1.1 - 0.01, 0.1), 1e-12, "hand");
  // Backward differences: a0 + a1 (3 - 4 z^-1 + z^-2) / 2dt + a2 (2 - 5 z^-1 + 4 z^-2 - z^-3)/dt^2.
  const cd z = z_at(300.0, kDt), q = 1.0 / z;
  const cd differences = 1.1 + 0.01 * (3.0 - 4.0 * q + q * q) / (2 * kDt) +
                         1e-4 * (2.0 - 5.0 * q + 4.0 * q * q - q * q * q) / (kDt * kDt);
  expect_near(realised(ats, 300.0), differences, 1e-9, "differences");
  expect_near(realised(ats, 2.0), ats.frequency_response(2.0), 1e-4, "low frequency");
  const Linearity l = ats.linearity();
  EXPECT_EQ(l.kind, Linearity::Kind::kFrozen);
  EXPECT_NE(l.note.find("frozen at their initial values a0 = 1.1, a1 = 10 ms"), std::string::npos)
      << l.note;
}

TEST(CompensatorDynamics, ModelBasedIsItsCAndItsTustinFilterAdaptedIsCorrectionTimesC) {
  PlantModel plant;
  plant.delay = 0.01;
  plant.append({1.0}, {0.02, 1.0});
  const ModelBasedInverse inverse(plant, 2, 40.0, kDt);
  const double w = 30.0;
  const cd s(0.0, w);
  const double wf = 2.0 * std::numbers::pi * 40.0, lead = 0.01 + 3.0 / wf;  // r_p + m = 3
  const cd hand =
      (0.02 * s + 1.0) * (1.0 + s * lead + s * s * lead * lead / 2.0) / std::pow(1.0 + s / wf, 3);
  expect_near(inverse.frequency_response(w), hand, 1e-10, "hand C(i w)");
  for (double w_d : {5.0, 300.0})
    expect_near(realised(inverse, w_d), inverse.frequency_response(warped(w_d)), 1e-9, "Tustin");
  const AdaptedModelBasedInverse adapted(inverse, adaptive_correction_defaults(), kDt);
  // The identity correction: H is C's; its realisation the correction's register then C's.
  expect_near(adapted.frequency_response(w), inverse.frequency_response(w), 1e-12, "identity");
  expect_near(realised(adapted, 300.0), realised(inverse, 300.0), 1e-9, "series");
  EXPECT_EQ(adapted.linearity().kind, Linearity::Kind::kFrozen);
}

// A chain is its compensator then its stages; its linearity names the block that limits it.
TEST(DelayChainDynamics, ChainIsCompensatorThenStagesAndNamesWhatItCannotRepresent) {
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(0.002, kDt));
  chain.add(std::make_unique<FirstOrderActuator>(0.01, kDt));
  chain.set_compensator(std::make_unique<PolynomialExtrapolation>(1, 0.003, 1, kDt));
  for (double w : {10.0, 400.0}) {
    const cd h = std::exp(cd(0.0, -0.002 * w)) / cd(1.0, 0.01 * w) *
                 (4.0 - 3.0 * std::exp(cd(0.0, -w * kDt)));
    expect_near(chain.frequency_response(w), h, 1e-12, "hand");
    const cd z = z_at(w, kDt), e = std::exp(-0.1);
    const cd discrete = (4.0 - 3.0 / z) / (z * z) * (1.0 - e) * z / (z - e);
    expect_near(realised(chain, w), discrete, 1e-12, "realisation");
  }
  EXPECT_EQ(chain.linearity().kind, Linearity::Kind::kTimeInvariant);
  chain.add(std::make_unique<JitterShift>(0.001, 0.0005, 3, kDt));
  const Linearity l = chain.linearity();
  EXPECT_EQ(l.kind, Linearity::Kind::kNone);
  EXPECT_NE(l.note.find("delay stage 3 jitter("), std::string::npos) << l.note;
}

}  // namespace
}  // namespace rths::core
