// The pre-run check of a lag with a damper's dashpot on the consortium's lab frame.
#include "core/loop_critical_delay.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "core/sparse_structure.h"

namespace rths::core {
namespace {

StructuralModel lab_frame() {
  StructuralModel model = make_shear_building({1000, 1000, 800}, {2e6, 2e6, 1.5e6});
  model.damping = rayleigh_damping(model.mass, model.stiffness, 0.03);
  return model;
}

// The consortium's storey damper (k 3e5 N/m, c 1e4 N s/m between floors 1 and 2).
DelayedPart storey_damper() {
  DelayedPart part;
  part.row = Vec::Unit(3, 1) - Vec::Unit(3, 0);
  part.stiffness = 3e5;
  part.damping = 1e4;
  return part;
}

// A study's damper: its dashpot leaves the model's C (C_N = C - c b b', here with a negative
// storey damping, which the modal check alone refuses) and comes back late with its force. The
// check takes the whole structure's modes and the coupled loop's limit; without a dashpot it is
// the plain check.
TEST(CoupledLoop, ThePreRunCheckTakesTheDashpotLate) {
  const StructuralModel whole = lab_frame();
  StructuralModel numerical = whole;
  const Vec b = Vec::Unit(3, 1) - Vec::Unit(3, 0);
  numerical.damping -= 1e4 * b * b.transpose();
  const DelayedPart damper = storey_damper();
  EXPECT_THROW(check_modal_critical_delay(numerical, 3e5 * b * b.transpose(),
                                          IntegratorKind::kExplicitNewmark, 0.001, 0.010),
               std::invalid_argument);
  const CriticalDelayCheck check = check_loop_critical_delay(
      numerical, {damper}, IntegratorKind::kExplicitNewmark, 0.001, 0.010);
  const CoupledLoopStability loop =
      coupled_loop_stability(numerical, {damper}, modal_analysis(numerical.mass, whole.stiffness));
  ASSERT_TRUE(check.continuous && loop.common_critical_lag);
  EXPECT_DOUBLE_EQ(*check.continuous, *loop.common_critical_lag);
  EXPECT_TRUE(check.coupled);
  EXPECT_NE(check.assumed.find("dashpots taken undelayed"), std::string::npos) << check.assumed;
  DelayedPart spring = damper;
  spring.damping = 0.0;
  const CriticalDelayCheck plain =
      check_loop_critical_delay(whole, {spring}, IntegratorKind::kExplicitNewmark, 0.001, 0.010);
  const CriticalDelayCheck direct = check_modal_critical_delay(
      whole, 3e5 * b * b.transpose(), IntegratorKind::kExplicitNewmark, 0.001, 0.010);
  EXPECT_EQ(plain.continuous, direct.continuous);
  EXPECT_EQ(plain.discrete, direct.discrete);
}

// A 100-DOF chain held sparse only takes its lowest 20 modes (a sparse eigensolver) where the
// dense model takes all 100: the limits agree to 1 % (the governing modes are the lowest; the
// coupled analysis keeps at most 24 either way), and the check says which it took.
TEST(CoupledLoop, ASparseModelsCheckMatchesTheDenseOneOnAHundredDofs) {
  const int n = 100;
  StructuralModel dense =
      make_shear_building(std::vector<double>(n, 1e5), std::vector<double>(n, 4e10));
  dense.damping = rayleigh_damping(dense.mass, dense.stiffness, 0.05);
  const StructuralModel sparse =
      make_sparse_model(dense.mass.sparseView(), dense.damping.sparseView(),
                        dense.stiffness.sparseView(), dense.influence);
  DelayedPart specimen;
  specimen.row = Vec::Unit(n, 0);
  specimen.stiffness = 4e10 / 3;
  const auto check = [&](const StructuralModel& model, double lag) {
    return check_loop_critical_delay(model, {specimen}, IntegratorKind::kExplicitNewmark,
                                     1.0 / 1024, lag);
  };
  for (const double lag : {0.0, 0.002, 0.02}) {
    const CriticalDelayCheck all = check(dense, lag), lowest = check(sparse, lag);
    ASSERT_EQ(all.continuous.has_value(), lowest.continuous.has_value()) << lag;
    if (all.continuous) EXPECT_NEAR(*lowest.continuous, *all.continuous, 0.01 * *all.continuous);
    ASSERT_EQ(all.discrete.has_value(), lowest.discrete.has_value()) << lag;
    if (all.discrete) EXPECT_NEAR(*lowest.discrete, *all.discrete, 0.01 * *all.discrete);
    EXPECT_EQ(lowest.past(), all.past()) << lag;
    EXPECT_NE(lowest.assumed.find("in the lowest 20 of 100 modes"), std::string::npos)
        << lowest.assumed;
  }
}

}  // namespace
}  // namespace rths::core
