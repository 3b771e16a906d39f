#include "core/exact_zoh.h"
#include "core/integrators.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/structure_response.h"

namespace rths::core {
namespace {

// A linear restoring force K u plus, at the trial of step `kick_step`, an extra force `kick` (N on
// DOF 0): what a measured experimental force looks like to the integrator.
class LinearWithKick final : public RestoringEvaluator {
 public:
  LinearWithKick(Mat k, int kick_step, double kick)
      : k_(std::move(k)), kick_step_(kick_step), kick_(kick) {}
  const Vec& trial(const Vec& u, const Vec& /*v*/, Mat* /*tangent*/) override {
    ++trials_;
    r_ = k_ * u;
    if (trials_ == kick_step_) r_[0] += kick_;
    return r_;
  }
  void commit() override {}
  bool repeatable() const override { return false; }

 private:
  Mat k_;
  int kick_step_;
  double kick_;
  int trials_ = 0;
  Vec r_;
};

// A damped SDOF under a constant force w from rest: the closed-form step response at t = h
// and its velocity, against x_1 = Gamma0 w; free vibration against Phi.
TEST(ExactDiscretisation, SdofMatchesTheClosedFormResponse) {
  const double m = 2.0, k = 800.0, zeta = 0.05, h = 0.013, w = 3.0;
  const double omega = std::sqrt(k / m), wd = omega * std::sqrt(1 - zeta * zeta);
  const double c = 2 * zeta * m * omega;
  const ExactDiscretisation d = exact_discretisation(Mat::Constant(1, 1, m), Mat::Constant(1, 1, c),
                                                     Mat::Constant(1, 1, k), h);
  const double e = std::exp(-zeta * omega * h);
  const double u_step = w / k * (1 - e * (std::cos(wd * h) + zeta * omega / wd * std::sin(wd * h)));
  const double v_step = w / k * e * (omega * omega / wd) * std::sin(wd * h);
  EXPECT_NEAR(d.gamma0(0, 0) * w, u_step, 1e-14);
  EXPECT_NEAR(d.gamma0(1, 0) * w, v_step, 1e-12);
  // Free vibration from u = 1: u(h) = e (cos + zeta w / wd sin).
  EXPECT_NEAR(d.phi(0, 0), e * (std::cos(wd * h) + zeta * omega / wd * std::sin(wd * h)), 1e-13);
  // A ramp from 0 to w over the step ends below the step response to w, above zero.
  EXPECT_GT(d.gamma1(0, 0) * w, 0.0);
  EXPECT_LT(d.gamma1(0, 0) * w, u_step);
}

// Without a held part the integrator is the exact linear response, at a step far past the explicit
// schemes' limit (omega_max dt = 8).
TEST(ExactZohIntegrator, WithoutAHeldForceItIsTheExactLinearResponse) {
  StructuralModel model = make_shear_building({1000, 1000, 800}, {4e6, 3e6, 1.5e6});
  model.damping = modal_damping(model.mass, model.stiffness, 0.03);
  const double dt = 8.0 / max_omega(model);
  GroundMotion motion;
  motion.dt = dt;
  for (int i = 0; i < 400; ++i)
    motion.acceleration.push_back(std::sin(0.37 * i) + 0.5 * std::cos(0.11 * i));
  const LinearResponse exact = exact_linear_response(model, motion);

  auto integrator = make_integrator(IntegratorKind::kExactZoh, model, dt);
  LinearWithKick restoring(model.stiffness, -1, 0.0);
  const Vec iota_m = model.mass * model.influence;
  integrator->initialize(Vec::Zero(3), Vec::Zero(3), Vec::Zero(3),
                         -iota_m * motion.acceleration[0]);
  double worst = 0.0;
  for (std::size_t k = 1; k < motion.acceleration.size(); ++k) {
    integrator->step(-iota_m * motion.acceleration[k], restoring);
    const auto row = static_cast<Eigen::Index>(k);
    worst = std::max(worst, (integrator->displacement().transpose() - exact.displacement.row(row))
                                .cwiseAbs()
                                .maxCoeff());
  }
  EXPECT_LT(worst, 1e-12 * exact.displacement.cwiseAbs().maxCoeff());
}

// The part of the restoring force beyond K_x u is held over the step after the one that measured
// it: a force measured at step 1 moves nothing at step 1 and moves the structure at step 2 by
// exactly Gamma0 (-force).
TEST(ExactZohIntegrator, TheMeasuredForceActsOverTheNextStep) {
  const StructuralModel model = make_sdof(0.5, 0.02, 10.0);
  const double dt = 1e-3, kick = 50.0;
  IntegratorParameters parameters;
  parameters.exact_stiffness = model.stiffness;
  auto integrator = make_integrator(IntegratorKind::kExactZoh, model, dt, parameters);
  LinearWithKick restoring(model.stiffness, 1, kick);
  integrator->initialize(Vec::Zero(1), Vec::Zero(1), Vec::Zero(1), Vec::Zero(1));
  integrator->step(Vec::Zero(1), restoring);
  EXPECT_EQ(integrator->displacement()[0], 0.0);
  // The acceleration of step 1 is from equilibrium with the force just measured.
  EXPECT_DOUBLE_EQ(integrator->acceleration()[0], -kick / model.mass(0, 0));
  integrator->step(Vec::Zero(1), restoring);
  const ExactDiscretisation d =
      exact_discretisation(model.mass, model.damping, model.stiffness, dt);
  EXPECT_DOUBLE_EQ(integrator->displacement()[0], -kick * d.gamma0(0, 0));
  EXPECT_DOUBLE_EQ(integrator->velocity()[0], -kick * d.gamma0(1, 0));
}

TEST(ExactZohIntegrator, NamedAndUnconditionallyStableForItsLinearPart) {
  EXPECT_EQ(to_string(IntegratorKind::kExactZoh), "exact-zoh");
  EXPECT_EQ(integrator_from_string("exact-zoh"), IntegratorKind::kExactZoh);
  EXPECT_TRUE(is_explicit(IntegratorKind::kExactZoh));
  EXPECT_NO_THROW(check_stability(IntegratorKind::kExactZoh, 1e6, 1.0, false));
}

TEST(ExactZohIntegrator, RefusesAStiffnessOfAnotherSize) {
  const StructuralModel model = make_shear_building({1, 1}, {100, 100});
  try {
    make_exact_zoh_integrator(model, 1e-3, Mat::Identity(3, 3));
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("3 x 3, the model has 2 DOFs"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rths::core
