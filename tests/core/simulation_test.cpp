#include "core/simulation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/metrics.h"

namespace rths::core {
namespace {

constexpr double kDt = 0.002;

GroundMotion sine_motion(double dt, double seconds, double frequency_hz = 1.5) {
  GroundMotion m{"sine", dt, {}};
  for (int k = 0; k * dt < seconds; ++k)
    m.acceleration.push_back(2.0 * std::sin(2 * M_PI * frequency_hz * k * dt));
  return m;
}

HybridSetup sdof_setup(double alpha, double delay,
                       IntegratorKind kind = IntegratorKind::kExplicitNewmark) {
  HybridSetup setup;
  setup.model = make_sdof(0.5, 0.05);
  setup.integrator = kind;
  setup.dt = kDt;
  setup.partition = partition_by_fraction(setup.model.storey_stiffness, alpha, linear_factory());
  if (delay > 0) {
    DelayChain chain;
    chain.add(std::make_unique<TimeShift>(delay, kDt));
    setup.delays.push_back(std::move(chain));
  }
  return setup;
}

std::vector<double> column(const Mat& m, int c) {
  return std::vector<double>(m.col(c).data(), m.col(c).data() + m.rows());
}

TEST(SimulationTest, ExplicitReferenceAgreesWithImplicitReference) {
  const GroundMotion motion = sine_motion(kDt, 4.0);
  const SimulationResult explicit_run = simulate(sdof_setup(0.5, 0.0), motion);
  const SimulationResult implicit_run =
      simulate(sdof_setup(0.5, 0.0, IntegratorKind::kNewmarkAverageAcceleration), motion);
  ASSERT_EQ(explicit_run.steps(), motion.acceleration.size());
  EXPECT_LT(nrmse(column(implicit_run.displacement, 0), column(explicit_run.displacement, 0)),
            2e-3);
}

TEST(SimulationTest, ZeroDelayShiftIsBitIdenticalToNoDelay) {
  const GroundMotion motion = sine_motion(kDt, 2.0);
  const SimulationResult plain = simulate(sdof_setup(0.5, 0.0), motion);
  HybridSetup zero = sdof_setup(0.5, 0.0);
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(0.0, kDt));
  zero.delays.push_back(std::move(chain));
  const SimulationResult shifted = simulate(zero, motion);
  EXPECT_EQ(plain.displacement, shifted.displacement);
}

TEST(SimulationTest, LagEnlargesAndLeadShrinksTheResponse) {
  const GroundMotion motion = sine_motion(kDt, 8.0, 2.0);  // at resonance
  const double reference =
      peak_abs(column(simulate(sdof_setup(1.0 / 3, 0.0), motion).displacement, 0));
  const double lagged =
      peak_abs(column(simulate(sdof_setup(1.0 / 3, 0.014), motion).displacement, 0));
  HybridSetup lead = sdof_setup(1.0 / 3, 0.0);
  DelayChain chain;
  chain.add(std::make_unique<Eq1Lead>(0.014));
  lead.delays.push_back(std::move(chain));
  const double led = peak_abs(column(simulate(lead, motion).displacement, 0));
  EXPECT_GT(lagged, 1.2 * reference);
  EXPECT_LT(led, 0.9 * reference);
}

TEST(SimulationTest, RecordsCommandRealisedAndForcePerActuator) {
  const GroundMotion motion = sine_motion(kDt, 1.0);
  const SimulationResult r = simulate(sdof_setup(0.5, 3 * kDt), motion);
  ASSERT_EQ(r.command.cols(), 1);
  for (Eigen::Index k = 3; k < r.command.rows(); ++k) {
    EXPECT_NEAR(r.realised(k, 0), r.command(k - 3, 0), 1e-15);
  }
  const double k_exp = 0.5 * r.measured_force(10, 0) / r.realised(10, 0) * 2;
  EXPECT_NEAR(k_exp, 0.5 * make_sdof(0.5, 0.05).stiffness(0, 0), 1e-6);
}

TEST(SimulationTest, UnstableDelayIsFlaggedDivergedNotRunToNaN) {
  const GroundMotion motion = sine_motion(kDt, 30.0);
  SimulationOptions options;
  options.divergence_bound = 10.0;
  const SimulationResult r = simulate(sdof_setup(1.0, 0.05), motion, options);
  EXPECT_TRUE(r.diverged);
  EXPECT_LT(r.steps(), motion.acceleration.size());
  EXPECT_TRUE(r.displacement.allFinite());
}

TEST(SimulationTest, RefusesBadSetups) {
  const GroundMotion motion = sine_motion(kDt, 1.0);
  EXPECT_THROW(simulate(sdof_setup(0.5, 0.01, IntegratorKind::kNewmarkAverageAcceleration), motion),
               std::invalid_argument);
  EXPECT_THROW(simulate(sdof_setup(0.5, 0.0), sine_motion(0.005, 1.0)), std::invalid_argument);
  HybridSetup too_coarse = sdof_setup(0.5, 0.0);
  too_coarse.dt = 0.2;  // omega dt = 2.5
  EXPECT_THROW(simulate(too_coarse, sine_motion(0.2, 5.0)), std::invalid_argument);
}

TEST(SimulationTest, ShearBuildingWithOneExperimentalStorey) {
  HybridSetup setup;
  setup.model = make_shear_building({1000.0, 1000.0}, {4e5, 3e5});
  setup.model.damping = rayleigh_damping(setup.model.mass, setup.model.stiffness, 0.05);
  setup.dt = kDt;
  setup.partition = partition_by_storeys(setup.model.storey_stiffness, {0}, linear_factory());
  const GroundMotion motion = sine_motion(kDt, 3.0);
  const SimulationResult reference = simulate(setup, motion);
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(0.01, kDt));
  setup.delays.push_back(std::move(chain));
  const SimulationResult delayed = simulate(setup, motion);
  ASSERT_EQ(reference.displacement.cols(), 2);
  // The actuator commands storey 1's drift, which is floor 1's displacement.
  EXPECT_EQ(column(reference.command, 0), column(reference.displacement, 0));
  EXPECT_GT(nrmse(column(reference.displacement, 1), column(delayed.displacement, 1)), 1e-3);
}

// A run that keeps some DOFs holds exactly the full run's columns of them, the peaks over
// every DOF, and a base shear equal to the inertial forces' sum iota^T M (a + iota a_g).
TEST(SimulationTest, KeptDofsHoldTheFullRunsColumnsAndThePeaksOfEveryDof) {
  HybridSetup setup;
  setup.model = make_shear_building({1000.0, 1200.0, 800.0}, {4e5, 3e5, 2e5});
  setup.model.damping = rayleigh_damping(setup.model.mass, setup.model.stiffness, 0.05);
  setup.dt = kDt;
  setup.partition = partition_by_storeys(setup.model.storey_stiffness, {0}, linear_factory());
  const GroundMotion motion = sine_motion(kDt, 3.0);
  const SimulationResult full = simulate(setup, motion);
  SimulationOptions options;
  options.kept_dofs = {0, 2};
  options.base_shear = true;
  options.peaks = true;
  const SimulationResult kept = simulate(setup, motion, options);
  options.kept_dofs = {};
  const SimulationResult full_with_peaks = simulate(setup, motion, options);
  ASSERT_EQ(kept.displacement.cols(), 2);
  EXPECT_EQ(kept.dofs, (std::vector<int>{0, 2}));
  EXPECT_EQ(kept.column_of_dof(2), 1);
  EXPECT_EQ(kept.column_of_dof(1), -1);
  EXPECT_EQ(column(kept.displacement, 1), column(full.displacement, 2));
  EXPECT_EQ(column(kept.velocity, 0), column(full.velocity, 0));
  EXPECT_EQ(column(kept.acceleration, 1), column(full.acceleration, 2));
  EXPECT_EQ(column(kept.measured_force, 0), column(full.measured_force, 0));
  EXPECT_EQ(kept.peak_displacement, full_with_peaks.peak_displacement);
  EXPECT_TRUE(full.base_shear.empty());
  EXPECT_TRUE(full.peak_displacement.empty());
  ASSERT_EQ(kept.base_shear.size(), kept.steps());
  double largest = 0.0;
  for (std::size_t k = 0; k < full.steps(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    EXPECT_DOUBLE_EQ(kept.peak_displacement[k], full.displacement.row(row).cwiseAbs().maxCoeff());
    EXPECT_DOUBLE_EQ(kept.peak_velocity[k], full.velocity.row(row).cwiseAbs().maxCoeff());
    EXPECT_DOUBLE_EQ(kept.peak_velocity[k],
                     std::abs(full.velocity(row, kept.peak_velocity_dof[k])));
    const Vec absolute =
        full.acceleration.row(row).transpose() + Vec::Ones(3) * motion.acceleration[k];
    const double inertial = (setup.model.mass * absolute).sum();
    EXPECT_NEAR(kept.base_shear[k], inertial, 1e-9 * std::max(1.0, std::abs(inertial)));
    largest = std::max(largest, std::abs(inertial));
  }
  EXPECT_GT(largest, 100.0);  // N: the check compared forces, not zeros
}

TEST(SimulationTest, RefusesKeptDofsOutsideTheModelOrOutOfOrder) {
  const GroundMotion motion = sine_motion(kDt, 0.1);
  SimulationOptions options;
  options.kept_dofs = {1};
  EXPECT_THROW(simulate(sdof_setup(0.5, 0.0), motion, options), std::invalid_argument);
  HybridSetup two;
  two.model = make_shear_building({1000.0, 1000.0}, {4e5, 3e5});
  two.dt = kDt;
  two.partition = partition_by_storeys(two.model.storey_stiffness, {0}, linear_factory());
  options.kept_dofs = {1, 0};
  EXPECT_THROW(simulate(two, motion, options), std::invalid_argument);
}

// The network's round trip (60 ms) and the actuator's lag (14 ms) as one shift on the command:
// the pair the link answers with (the specimen's drift and force) is 74 ms old.
HybridSetup remote_setup(double stiffness_factor, bool adapt, double bound = 0.0) {
  HybridSetup setup = sdof_setup(1.0 / 3, 0.074);
  PredictorParameters p;
  p.stiffness = stiffness_factor * setup.partition.experimental[0]->initial_stiffness();
  p.adapt = adapt;
  p.max_relative_error = bound;
  setup.predictors = {p};
  return setup;
}

// RMS of (run - reference) over steps [from, to) against the reference's RMS over them.
double relative_rms(const SimulationResult& run, const SimulationResult& reference,
                    std::size_t from, std::size_t to) {
  double e = 0.0, r = 0.0;
  for (std::size_t k = from; k < to; ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    const double d = run.displacement(row, 0) - reference.displacement(row, 0);
    e += d * d;
    r += reference.displacement(row, 0) * reference.displacement(row, 0);
  }
  return std::sqrt(e / r);
}

TEST(SimulationTest, ForcePredictorHoldsA74msLoopThatDivergesWithoutIt) {
  const GroundMotion motion = sine_motion(kDt, 10.0, 2.0);
  const SimulationResult lag_free = simulate(sdof_setup(1.0 / 3, 0.0), motion);
  const SimulationResult bare = simulate(sdof_setup(1.0 / 3, 0.074), motion);
  const double reference_peak = peak_abs(column(lag_free.displacement, 0));
  EXPECT_TRUE(bare.diverged || peak_abs(column(bare.displacement, 0)) > 10 * reference_peak);
  const SimulationResult compensated = simulate(remote_setup(1.0, true), motion);
  ASSERT_FALSE(compensated.diverged);
  ASSERT_EQ(compensated.steps(), lag_free.steps());
  // The right model: the loop's lag acts on an error of rounding size only.
  EXPECT_LT(relative_rms(compensated, lag_free, 0, lag_free.steps()), 1e-9);
  const double k_e =
      compensated.measured_force.cwiseAbs().maxCoeff() / compensated.realised.cwiseAbs().maxCoeff();
  EXPECT_LT(compensated.prediction_error.cwiseAbs().maxCoeff(), 1e-9 * k_e * reference_peak);
  EXPECT_TRUE(compensated.held.empty());
}

TEST(SimulationTest, ForcePredictorLearnsAModelThirtyPercentSoftWithinFiveSeconds) {
  const GroundMotion motion = sine_motion(kDt, 10.0, 2.0);
  const SimulationResult lag_free = simulate(sdof_setup(1.0 / 3, 0.0), motion);
  const SimulationResult fixed = simulate(remote_setup(0.7, false), motion);
  const SimulationResult adapted = simulate(remote_setup(0.7, true), motion);
  ASSERT_FALSE(adapted.diverged);
  const std::size_t five_s = static_cast<std::size_t>(5.0 / kDt);
  const double fixed_error = relative_rms(fixed, lag_free, five_s, lag_free.steps());
  const double adapted_error = relative_rms(adapted, lag_free, five_s, lag_free.steps());
  EXPECT_LT(adapted_error, 0.01);
  EXPECT_GT(fixed_error, 10 * adapted_error);
}

TEST(SimulationTest, ForcePredictorPastItsBoundStopsTheRunNamingTheLink) {
  const GroundMotion motion = sine_motion(kDt, 10.0, 2.0);
  const SimulationResult held = simulate(remote_setup(0.5, false, 0.2), motion);
  ASSERT_FALSE(held.held.empty());
  EXPECT_NE(held.held.find("force predictor of actuator 1 (link of storey 1)"), std::string::npos)
      << held.held;
  EXPECT_NE(held.held.find("past its bound of 20 %"), std::string::npos) << held.held;
  EXPECT_LT(held.steps(), motion.acceleration.size());
  // The same bound with the model fitted online never trips.
  EXPECT_TRUE(simulate(remote_setup(0.5, true, 0.2), motion).held.empty());
}

TEST(SimulationTest, ForcePredictorsMustMatchTheActuators) {
  HybridSetup setup = remote_setup(1.0, true);
  setup.predictors.push_back(std::nullopt);
  EXPECT_THROW(simulate(setup, sine_motion(kDt, 1.0)), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
