#include "core/restoring_force.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace rths::core {
namespace {

constexpr double kK0 = 1000.0;  // N/m
constexpr double kUy = 0.01;    // m
constexpr double kFy = kK0 * kUy;
constexpr double kB = 0.1;

// Drives a model from drift `from` (its committed drift) through `targets` in increments of at
// most `increment`; returns the (u, f) pairs visited.
struct Path {
  std::vector<double> drift, force;
};
Path drive(RestoringForceModel& model, const std::vector<double>& targets, double increment,
           double from = 0.0) {
  Path path{{from}, {model.trial(from).force}};
  double u = from;
  for (double target : targets) {
    const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(target - u) / increment)));
    const double start = u;
    for (int i = 1; i <= steps; ++i) {
      u = start + (target - start) * i / steps;
      path.drift.push_back(u);
      path.force.push_back(model.step(u));
    }
  }
  return path;
}

// Area enclosed by the path (trapezoid rule on f du), i.e. the energy dissipated (J).
double loop_area(const Path& path) {
  double area = 0.0;
  for (std::size_t i = 1; i < path.drift.size(); ++i) {
    area += 0.5 * (path.force[i] + path.force[i - 1]) * (path.drift[i] - path.drift[i - 1]);
  }
  return area;
}

TEST(LinearSpring, ForceAndTangent) {
  LinearSpring spring(2.5e6);
  const ForceState s = spring.trial(-0.002);
  EXPECT_DOUBLE_EQ(s.force, -5000.0);
  EXPECT_DOUBLE_EQ(s.tangent, 2.5e6);
  EXPECT_DOUBLE_EQ(spring.step(0.004), 10000.0);
  EXPECT_DOUBLE_EQ(spring.initial_stiffness(), 2.5e6);
  EXPECT_NE(spring.clone()->describe().find("linear"), std::string::npos);
}

TEST(BilinearKinematic, MonotonicYieldAndPostYieldSlope) {
  BilinearKinematic model(kK0, kUy, kB);
  EXPECT_DOUBLE_EQ(model.step(0.5 * kUy), 0.5 * kFy);
  EXPECT_DOUBLE_EQ(model.trial(0.5 * kUy).tangent, kK0);
  EXPECT_DOUBLE_EQ(model.step(kUy), kFy);  // yield exactly at fy
  const double f2 = model.step(2 * kUy);
  const double f3 = model.step(3 * kUy);
  EXPECT_DOUBLE_EQ(f2, kFy + kB * kK0 * kUy);
  EXPECT_NEAR((f3 - f2) / kUy, kB * kK0, 1e-9);
  EXPECT_DOUBLE_EQ(model.trial(3.5 * kUy).tangent, kB * kK0);
}

TEST(BilinearKinematic, CyclicLoopShape) {
  BilinearKinematic model(kK0, kUy, kB);
  const double peak = 3 * kUy;
  const Path path = drive(model, {peak, -peak, peak}, kUy / 20);
  // Force at the peak: on the upper band b k0 u + (1 - b) fy.
  const double f_peak = kB * kK0 * peak + (1 - kB) * kFy;
  // Walk the unloading branch from +peak: elastic (slope k0) over a force range of 2 fy
  // (kinematic hardening: the elastic range keeps its size), then the lower band.
  for (std::size_t i = 0; i < path.drift.size(); ++i) {
    const double u = path.drift[i], f = path.force[i];
    const double upper = kB * kK0 * u + (1 - kB) * kFy, lower = kB * kK0 * u - (1 - kB) * kFy;
    EXPECT_LE(f, upper + 1e-9) << i;
    EXPECT_GE(f, lower - 1e-9) << i;
  }
  BilinearKinematic fresh(kK0, kUy, kB);
  fresh.step(peak);
  EXPECT_DOUBLE_EQ(fresh.step(peak), f_peak);
  const double u_elastic_end = peak - 2 * kFy / kK0;  // where the elastic unloading meets the band
  EXPECT_NEAR(fresh.step(peak - 0.5 * (peak - u_elastic_end)), f_peak - kFy, 1e-9);
  EXPECT_NEAR(fresh.step(u_elastic_end), f_peak - 2 * kFy, 1e-9);
  EXPECT_NEAR(fresh.step(u_elastic_end), kB * kK0 * u_elastic_end - (1 - kB) * kFy, 1e-9);
  const double before = fresh.step(-kUy);
  const double after = fresh.step(-2 * kUy);
  EXPECT_NEAR((after - before) / -kUy, kB * kK0, 1e-9);  // reverse post-yield slope
  // Symmetric: the negative peak mirrors the positive one.
  EXPECT_NEAR(fresh.step(-peak), -f_peak, 1e-9);
  // A closed cycle dissipates energy. The loop is a parallelogram: area = 4 (1 - b) fy *
  // (peak - uy) for a symmetric cycle between +/- peak, here from the analytic branches.
  BilinearKinematic cycle(kK0, kUy, kB);
  drive(cycle, {peak}, kUy / 20);
  Path closed = drive(cycle, {-peak, peak}, kUy / 200, peak);
  EXPECT_NEAR(loop_area(closed), 4 * (1 - kB) * kFy * (peak - kUy), 1e-3 * kFy * kUy);
}

TEST(BilinearKinematic, TrialDoesNotMutateCommittedState) {
  BilinearKinematic model(kK0, kUy, kB);
  model.step(2 * kUy);
  const ForceState first = model.trial(1.5 * kUy);
  model.trial(10 * kUy);  // far past yield, not committed
  model.trial(-10 * kUy);
  const ForceState again = model.trial(1.5 * kUy);
  EXPECT_DOUBLE_EQ(first.force, again.force);
  EXPECT_DOUBLE_EQ(first.tangent, again.tangent);
  model.commit();
  EXPECT_DOUBLE_EQ(model.step(1.5 * kUy), first.force);
}

TEST(BilinearKinematic, CloneIsIndependentAndResetRestoresOrigin) {
  BilinearKinematic model(kK0, kUy, kB);
  model.step(3 * kUy);
  auto copy = model.clone();
  model.step(-3 * kUy);
  // The copy still unloads elastically from +3 uy.
  EXPECT_NEAR(copy->step(2.5 * kUy), kB * kK0 * 3 * kUy + (1 - kB) * kFy - 0.5 * kFy, 1e-9);
  model.reset();
  EXPECT_DOUBLE_EQ(model.step(0.5 * kUy), 0.5 * kFy);
}

TEST(BilinearKinematic, RejectsBadParameters) {
  EXPECT_THROW(BilinearKinematic(0.0, kUy, kB), std::invalid_argument);
  EXPECT_THROW(BilinearKinematic(kK0, -kUy, kB), std::invalid_argument);
  EXPECT_THROW(BilinearKinematic(kK0, kUy, 1.5), std::invalid_argument);
}

TEST(BilinearKinematic, RatioOneIsLinear) {
  BilinearKinematic model(kK0, kUy, 1.0);
  const Path path = drive(model, {5 * kUy, -5 * kUy}, kUy / 3);
  for (std::size_t i = 0; i < path.drift.size(); ++i) {
    EXPECT_NEAR(path.force[i], kK0 * path.drift[i], 1e-9);
  }
}

constexpr double kAlpha = 0.1;

TEST(BoucWen, MonotonicLoadingMatchesClosedFormForNOne) {
  // n = 1, beta = gamma: on loading from rest, dz/du = 1 - z / uy, so z = uy (1 - e^(-u/uy)).
  BoucWen model(kK0, kUy, kAlpha, 1.0, 0.5);
  for (int i = 1; i <= 100; ++i) {
    const double u = i * 0.1 * kUy;
    const double f = model.step(u);
    const double z = kUy * (1.0 - std::exp(-u / kUy));
    EXPECT_NEAR(f, kAlpha * kK0 * u + (1 - kAlpha) * kK0 * z, 1e-9 * kFy) << u;
  }
}

TEST(BoucWen, SaturatesAtTheYieldForce) {
  for (double n : {1.0, 2.0, 5.0}) {
    BoucWen model(kK0, kUy, kAlpha, n, 0.5);
    const double u = 20 * kUy;
    const double f = model.step(u);  // one big increment: the sub-steps must cope
    EXPECT_NEAR(f - kAlpha * kK0 * u, (1 - kAlpha) * kFy, 1e-3 * kFy) << n;
    EXPECT_NEAR(model.trial(u + 1e-6).tangent, kAlpha * kK0, 1e-3 * kK0) << n;
  }
}

TEST(BoucWen, LargeIncrementEqualsManySmallOnes) {
  BoucWen coarse(kK0, kUy, kAlpha, 2.0, 0.5), fine(kK0, kUy, kAlpha, 2.0, 0.5);
  const double f_coarse = coarse.step(4 * kUy);
  const Path path = drive(fine, {4 * kUy}, kUy / 100);
  EXPECT_NEAR(f_coarse, path.force.back(), 1e-6 * kFy);
}

TEST(BoucWen, DissipatesEnergyAndIsNearlyLinearForTinyAmplitude) {
  BoucWen model(kK0, kUy, kAlpha, 2.0, 0.5);
  drive(model, {3 * kUy}, kUy / 20);
  const Path cycle = drive(model, {-3 * kUy, 3 * kUy}, kUy / 50, 3 * kUy);
  EXPECT_GT(loop_area(cycle), 0.5 * (1 - kAlpha) * kFy * kUy);  // a fat loop, not a line
  // Below 1e-3 uy, |z|^n is ~1e-6: the force is k0 u to better than 1e-5.
  BoucWen tiny(kK0, kUy, kAlpha, 2.0, 0.5);
  drive(tiny, {1e-3 * kUy}, 1e-5 * kUy);
  const Path small = drive(tiny, {-1e-3 * kUy, 1e-3 * kUy}, 1e-5 * kUy, 1e-3 * kUy);
  for (std::size_t i = 0; i < small.drift.size(); ++i) {
    EXPECT_NEAR(small.force[i], kK0 * small.drift[i], 1e-5 * kK0 * 1e-3 * kUy) << i;
  }
  EXPECT_LT(std::abs(loop_area(small)), 1e-6 * loop_area(cycle));
}

TEST(BoucWen, TrialDoesNotMutateAndCloneIsIndependent) {
  BoucWen model(kK0, kUy, kAlpha, 2.0, 0.5);
  model.step(2 * kUy);
  const ForceState first = model.trial(1.2 * kUy);
  model.trial(-8 * kUy);
  EXPECT_DOUBLE_EQ(model.trial(1.2 * kUy).force, first.force);
  auto copy = model.clone();
  model.step(-5 * kUy);
  EXPECT_DOUBLE_EQ(copy->trial(1.2 * kUy).force, first.force);
  model.reset();
  BoucWen fresh(kK0, kUy, kAlpha, 2.0, 0.5);
  EXPECT_DOUBLE_EQ(model.step(0.3 * kUy), fresh.step(0.3 * kUy));
}

TEST(BoucWen, RejectsBadParameters) {
  EXPECT_THROW(BoucWen(-1.0, kUy, kAlpha, 2.0, 0.5), std::invalid_argument);
  EXPECT_THROW(BoucWen(kK0, 0.0, kAlpha, 2.0, 0.5), std::invalid_argument);
  EXPECT_THROW(BoucWen(kK0, kUy, 1.2, 2.0, 0.5), std::invalid_argument);
  EXPECT_THROW(BoucWen(kK0, kUy, kAlpha, 0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(BoucWen(kK0, kUy, kAlpha, 2.0, -0.1), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core

namespace rths::core {
namespace {

TEST(InertialSpecimenTest, AddsInertiaAndDampingFromBackwardDifferences) {
  const double h = 0.01;
  InertialSpecimen specimen(std::make_unique<LinearSpring>(100.0), 2.0, 3.0, h);
  EXPECT_EQ(specimen.initial_stiffness(), 100.0);
  // x: 0, then 1e-3, 3e-3: v = 0.2 m/s, a = (3e-3 - 2e-3 + 0) / h^2 = 10 m/s^2 at the third.
  EXPECT_DOUBLE_EQ(specimen.step(1e-3), 2.0 * 1e-3 / (h * h) + 3.0 * 1e-3 / h + 0.1);
  const ForceState s = specimen.trial(3e-3);
  EXPECT_NEAR(s.force, 2.0 * 10.0 + 3.0 * 0.2 + 0.3, 1e-12);
  EXPECT_DOUBLE_EQ(s.tangent, 100.0 + 3.0 / h + 2.0 / (h * h));
  // A trial does not move the committed history; a clone carries it.
  EXPECT_NEAR(specimen.trial(3e-3).force, s.force, 1e-15);
  auto copy = specimen.clone();
  EXPECT_EQ(copy->trial(3e-3).force, s.force);
  specimen.reset();
  EXPECT_DOUBLE_EQ(specimen.trial(0.0).force, 0.0);
  EXPECT_THROW(InertialSpecimen(std::make_unique<LinearSpring>(1.0), -1.0, 0.0, h),
               std::invalid_argument);
  EXPECT_THROW(InertialSpecimen(std::make_unique<LinearSpring>(1.0), 1.0, 0.0, 0.0),
               std::invalid_argument);
}

// A hysteretic model is alpha k0 u + (1 - alpha) k0 uy z(u) with z its parts' unit hysteresis
// driven along the same path (what a force predictor fits as k and h): along a loop that yields
// both ways, to rounding, and |z| stays within 1.
TEST(HystereticModel, PartsRebuildTheForceAlongALoop) {
  const std::vector<double> targets = {2.5 * kUy, -3 * kUy, 0.5 * kUy, -0.2 * kUy, 4 * kUy};
  BilinearKinematic bilinear(kK0, kUy, kB);
  BoucWen bouc_wen(kK0, kUy, 0.2, 2.0, 0.3);
  for (HystereticModel* model : std::vector<HystereticModel*>{&bilinear, &bouc_wen}) {
    const HystereticModel::Parts parts = model->parts();
    EXPECT_EQ(parts.yield_drift, kUy) << model->describe();
    const Path whole = drive(*model, targets, kUy / 7);
    const Path z = drive(*parts.unit_hysteresis, targets, kUy / 7);
    ASSERT_EQ(whole.force.size(), z.force.size());
    double largest = 0.0;
    for (std::size_t i = 0; i < z.force.size(); ++i) {
      const double rebuilt = parts.linear_ratio * kK0 * whole.drift[i] +
                             (1 - parts.linear_ratio) * kK0 * kUy * z.force[i];
      EXPECT_NEAR(rebuilt, whole.force[i], 1e-9 * kFy) << model->describe() << " at " << i;
      largest = std::max(largest, std::abs(z.force[i]));
    }
    EXPECT_LE(largest, 1.0 + 1e-12) << model->describe();
    EXPECT_GT(largest, 0.9) << model->describe();
  }
  EXPECT_EQ(bilinear.parts().linear_ratio, kB);
  EXPECT_EQ(bouc_wen.parts().linear_ratio, 0.2);
}

// A model's description and its refusals name each parameter as messages print numbers (%g).
TEST(RestoringForceText, DescriptionsAndRefusalsNameTheirParameters) {
  EXPECT_EQ(LinearSpring(2.5e6).describe(), "linear(k = 2.5e+06 N/m)");
  EXPECT_EQ(BilinearKinematic(kK0, kUy, kB).describe(),
            "bilinear-kinematic(k0 = 1000 N/m, fy = 10 N, b = 0.1)");
  EXPECT_EQ(BoucWen(kK0, kUy, kB, 2.0, 0.5).describe(),
            "bouc-wen(k0 = 1000 N/m, uy = 0.01 m, alpha = 0.1, n = 2, beta uy^n = 0.5)");
  try {
    BoucWen(kK0, kUy, kB, -1.5, 0.5);
    FAIL() << "a negative exponent was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("BoucWen: exponent n must be > 0, got -1.5"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rths::core
