// The pre-run check of a lag with a damper's dashpot on the consortium's lab frame.
#include "core/loop_critical_delay.h"

#include <gtest/gtest.h>

#include <stdexcept>

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

}  // namespace
}  // namespace rths::core
