#include "core/structure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rths::core {
namespace {

constexpr double kTolerance = 1e-10;

TEST(StructureTest, SdofHasRequestedPeriodAndDamping) {
  const StructuralModel model = make_sdof(0.5, 0.05, 1000.0);
  const double omega = 2.0 * std::numbers::pi / 0.5;
  EXPECT_NEAR(model.stiffness(0, 0), 1000.0 * omega * omega, 1e-6);
  EXPECT_NEAR(model.damping(0, 0), 2.0 * 0.05 * 1000.0 * omega, 1e-9);
  EXPECT_NEAR(max_omega(model), omega, 1e-9);
}

TEST(StructureTest, ShearBuildingStiffnessIsTridiagonalFromStoreys) {
  const StructuralModel model = make_shear_building({1.0, 2.0, 3.0}, {10.0, 20.0, 30.0});
  Mat expected(3, 3);
  expected << 30, -20, 0, -20, 50, -30, 0, -30, 30;
  EXPECT_TRUE(model.stiffness.isApprox(expected));
  EXPECT_TRUE(model.influence.isApprox(Vec::Ones(3)));
}

TEST(StructureTest, TwoStoreyFrequenciesMatchClosedForm) {
  // m = 1, k = 1 per storey: omega^2 = (3 -/+ sqrt(5)) / 2.
  const StructuralModel model = make_shear_building({1.0, 1.0}, {1.0, 1.0});
  const Modes modes = modal_analysis(model.mass, model.stiffness);
  EXPECT_NEAR(modes.omega(0), std::sqrt((3.0 - std::sqrt(5.0)) / 2.0), kTolerance);
  EXPECT_NEAR(modes.omega(1), std::sqrt((3.0 + std::sqrt(5.0)) / 2.0), kTolerance);
  const Mat orthogonality = modes.shapes.transpose() * model.mass * modes.shapes;
  EXPECT_TRUE(orthogonality.isIdentity(1e-10));
}

double modal_ratio(const Mat& mass, const Mat& stiffness, const Mat& damping, int mode) {
  const Modes modes = modal_analysis(mass, stiffness);
  const Vec phi = modes.shapes.col(mode);
  return phi.dot(damping * phi) / (2.0 * modes.omega(mode));
}

TEST(StructureTest, RayleighDampingMeetsRatioAtBothChosenModes) {
  const StructuralModel model = make_shear_building({2.0, 1.5, 1.0}, {300.0, 200.0, 100.0});
  const Mat c = rayleigh_damping(model.mass, model.stiffness, 0.05, 1, 3);
  EXPECT_NEAR(modal_ratio(model.mass, model.stiffness, c, 0), 0.05, 1e-10);
  EXPECT_NEAR(modal_ratio(model.mass, model.stiffness, c, 2), 0.05, 1e-10);
  // Between the anchors Rayleigh damping dips below the target.
  EXPECT_LT(modal_ratio(model.mass, model.stiffness, c, 1), 0.05);
}

TEST(StructureTest, ModalDampingMeetsRatioInEveryMode) {
  const StructuralModel model = make_shear_building({2.0, 1.5, 1.0}, {300.0, 200.0, 100.0});
  const Mat c = modal_damping(model.mass, model.stiffness, 0.03);
  for (int mode = 0; mode < 3; ++mode) {
    EXPECT_NEAR(modal_ratio(model.mass, model.stiffness, c, mode), 0.03, 1e-10);
  }
}

TEST(StructureTest, RejectsBadInput) {
  EXPECT_THROW(make_sdof(-0.5, 0.05), std::invalid_argument);
  EXPECT_THROW(make_sdof(0.5, -0.05), std::invalid_argument);
  EXPECT_THROW(make_shear_building({}, {}), std::invalid_argument);
  EXPECT_THROW(make_shear_building({1.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(make_shear_building({1.0, 0.0}, {1.0, 2.0}), std::invalid_argument);
  const StructuralModel two = make_shear_building({1.0, 1.0}, {1.0, 1.0});
  EXPECT_THROW(rayleigh_damping(two.mass, two.stiffness, 0.05, 1, 3), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
