// The coupled critical delay against the SDOF closed form and against the characteristic equation
// of one delayed storey written independently here (full coordinates, the matrix determinant
// lemma), on the lab's 3-DOF frame.
#include "core/coupled_stability.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <optional>

#include "core/stability.h"
#include "core/substructure.h"

namespace rths::core {
namespace {

StructuralModel lab_frame() {
  StructuralModel model = make_shear_building({1000, 1000, 800}, {2e6, 2e6, 1.5e6});
  model.damping = rayleigh_damping(model.mass, model.stiffness, 0.03);
  return model;
}

// k_e b b^T for a storey element of stiffness k between DOFs i and j (0-based).
Mat storey_element(int n, int i, int j, double k) {
  Vec b = Vec::Zero(n);
  b[j] = 1.0;
  b[i] = -1.0;
  return k * b * b.transpose();
}

// One delayed element k_e b b^T: det(A + z k_e b b^T) = det(A) (1 + z k_e b' A^-1 b), so a root
// crosses at s = i w when |k_e g(w)| = 1 with g = b' (K - k_e b b' - M w^2 + i w C)^-1 b, and
// then z = e^{-i w tau} = -1 / (k_e g). Scanned on a linear grid up to 5 omega_max and bisected.
std::optional<double> one_delayed_part(const StructuralModel& m, const Vec& b, double k) {
  using Complex = std::complex<double>;
  const Mat k_numerical = m.stiffness - k * b * b.transpose();
  const auto g = [&](double w) {
    const Eigen::MatrixXcd a =
        (k_numerical - w * w * m.mass).cast<Complex>() + Complex(0, w) * m.damping.cast<Complex>();
    return Complex(b.cast<Complex>().dot(a.fullPivLu().solve(b.cast<Complex>())));
  };
  const auto excess = [&](double w) { return std::abs(k * g(w)) - 1.0; };
  std::optional<double> smallest;
  const double top = 5.0 * max_omega(m);
  const int grid = 200000;
  for (int i = 1; i < grid; ++i) {
    double lo = top * (i - 1) / grid + 1e-6, hi = top * i / grid;
    if ((excess(lo) > 0) == (excess(hi) > 0)) continue;
    for (int n = 0; n < 80; ++n) {
      const double mid = 0.5 * (lo + hi);
      ((excess(mid) > 0) == (excess(lo) > 0) ? lo : hi) = mid;
    }
    const double w = 0.5 * (lo + hi);
    double theta = -std::arg(-1.0 / (k * g(w)));
    if (theta < 0) theta += 2 * std::numbers::pi;
    if (!smallest || theta / w < *smallest) smallest = theta / w;
  }
  return smallest;
}

TEST(CoupledStability, OneDofIsTheSdofClosedForm) {
  const double period = 0.5, zeta = 0.05, alpha = 0.4;
  StructuralModel sdof = make_sdof(period, zeta, 1000.0);
  const Mat k_e = alpha * sdof.stiffness;
  const CoupledStability coupled =
      coupled_critical_delay(sdof, k_e, modal_analysis(sdof.mass, sdof.stiffness));
  const ContinuousStability closed = continuous_critical_delay(period, zeta, alpha);
  ASSERT_TRUE(coupled.critical_delay && closed.critical_delay);
  EXPECT_NEAR(*coupled.critical_delay, *closed.critical_delay, 1e-9 * *closed.critical_delay);
  EXPECT_EQ(coupled.parts, 1);
}

TEST(CoupledStability, AStoreySpecimenAgreesWithItsCharacteristicEquation) {
  const StructuralModel frame = lab_frame();
  for (const double k : {0.5e6, 1e6, 2e6}) {
    const Mat k_e = storey_element(3, 0, 1, k);
    const CoupledStability coupled =
        coupled_critical_delay(frame, k_e, modal_analysis(frame.mass, frame.stiffness));
    const std::optional<double> independent =
        one_delayed_part(frame, Vec::Unit(3, 1) - Vec::Unit(3, 0), k);
    ASSERT_TRUE(coupled.critical_delay.has_value()) << k;
    ASSERT_TRUE(independent.has_value()) << k;
    EXPECT_NEAR(*coupled.critical_delay, *independent, 0.01 * *independent) << k;
    EXPECT_EQ(coupled.modes_kept, 3);
    EXPECT_NE(coupled.assumed.find("all 3 modes"), std::string::npos) << coupled.assumed;
  }
}

TEST(CoupledStability, AStoreyIsNotTheGroundedSpringAtItsFloor) {
  // The researcher's mistake: 0.2e6 N/m of storey 2 as a spring from floor 2 to the ground. As
  // the storey's element it is stable for every lag (its force never outgrows the rest of the
  // storey); as the grounded spring it is not (17 ms, by the independent equation above).
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  Mat grounded = Mat::Zero(3, 3);
  grounded(1, 1) = 0.2e6;
  EXPECT_FALSE(coupled_critical_delay(frame, storey_element(3, 0, 1, 0.2e6), modes)
                   .critical_delay.has_value());
  const auto spring = coupled_critical_delay(frame, grounded, modes);
  const auto independent = one_delayed_part(frame, Vec::Unit(3, 1), 0.2e6);
  ASSERT_TRUE(spring.critical_delay && independent);
  EXPECT_NEAR(*spring.critical_delay, *independent, 0.01 * *independent);
}

TEST(CoupledStability, TwoDelayedStoreysTolerateLessThanEitherAlone) {
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  const Mat first = storey_element(3, 0, 1, 1e6), second = storey_element(3, 1, 2, 0.75e6);
  const auto both = coupled_critical_delay(frame, first + second, modes);
  const auto one = coupled_critical_delay(frame, first, modes);
  const auto other = coupled_critical_delay(frame, second, modes);
  ASSERT_TRUE(both.critical_delay && one.critical_delay && other.critical_delay);
  EXPECT_EQ(both.parts, 2);
  EXPECT_LT(*both.critical_delay, std::min(*one.critical_delay, *other.critical_delay));
}

TEST(CoupledStability, ProportionalSplitsDecoupleAndKeepTheModalCheck) {
  const StructuralModel frame = lab_frame();
  const Modes modes = modal_analysis(frame.mass, frame.stiffness);
  EXPECT_TRUE(modes_decouple(frame, 0.3 * frame.stiffness, modes));
  EXPECT_FALSE(modes_decouple(frame, storey_element(3, 0, 1, 1e6), modes));
  // And the pre-run check says which analysis it used.
  const CriticalDelayCheck check = check_modal_critical_delay(
      frame, storey_element(3, 0, 1, 1e6), IntegratorKind::kExplicitNewmark, 0.001, 0.004);
  EXPECT_NE(check.assumed.find("coupled analysis"), std::string::npos) << check.assumed;
  EXPECT_TRUE(check.modal_continuous.has_value());
  const CriticalDelayCheck proportional = check_modal_critical_delay(
      frame, 0.3 * frame.stiffness, IntegratorKind::kExplicitNewmark, 0.001, 0.004);
  EXPECT_NE(proportional.assumed.find("modal approximation"), std::string::npos);
  EXPECT_FALSE(proportional.modal_continuous.has_value());
}

}  // namespace
}  // namespace rths::core
