#include "core/restoring_force.h"

#include "core/number_text.h"

#include "core/precondition.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rths::core {
namespace {

bool positive_finite(double x) { return x > 0.0 && std::isfinite(x); }

}  // namespace

// ---------------------------------------------------------------------------------------------
LinearSpring::LinearSpring(double stiffness) : k_(stiffness) {
  require(std::isfinite(stiffness), "LinearSpring: stiffness must be finite");
}

ForceState LinearSpring::trial(double drift) { return {k_ * drift, k_}; }

std::unique_ptr<RestoringForceModel> LinearSpring::clone() const {
  return std::make_unique<LinearSpring>(*this);
}

std::string LinearSpring::describe() const { return "linear(k = " + format_number(k_) + " N/m)"; }

// ---------------------------------------------------------------------------------------------
BilinearKinematic::BilinearKinematic(double k0, double yield_drift, double post_yield_ratio)
    : HystereticModel(k0), fy_(k0 * yield_drift), b_(post_yield_ratio) {
  require(positive_finite(k0), "BilinearKinematic: k0 must be > 0, got " + format_number(k0));
  require(positive_finite(yield_drift),
          "BilinearKinematic: yield drift must be > 0, got " + format_number(yield_drift));
  require(post_yield_ratio >= 0.0 && post_yield_ratio <= 1.0,
          "BilinearKinematic: post-yield ratio b must be in [0, 1], got " +
              format_number(post_yield_ratio));
}

// Elastic predictor from the committed state, then return to the band b k0 u +/- (1 - b) fy.
ForceState BilinearKinematic::trial(double drift) {
  trial_.drift = drift;
  const double predictor = committed_.internal + k0_ * (drift - committed_.drift);
  const double centre = b_ * k0_ * drift;
  const double half_width = (1.0 - b_) * fy_;
  if (predictor > centre + half_width) {
    trial_.internal = centre + half_width;
    return {trial_.internal, b_ * k0_};
  }
  if (predictor < centre - half_width) {
    trial_.internal = centre - half_width;
    return {trial_.internal, b_ * k0_};
  }
  trial_.internal = predictor;
  return {trial_.internal, k0_};
}

std::unique_ptr<RestoringForceModel> BilinearKinematic::clone() const {
  return std::make_unique<BilinearKinematic>(*this);
}

// b k0 u + (1 - b) k0 p(u), p the elastic-perfectly-plastic drift within +/- uy: the return
// mapping above clamps p exactly as it clamps the force to its band.
HystereticModel::Parts BilinearKinematic::parts() const {
  const double uy = fy_ / k0_;
  return {b_, uy, std::make_unique<BilinearKinematic>(1.0 / uy, uy, 0.0)};
}

std::string BilinearKinematic::describe() const {
  return "bilinear-kinematic(k0 = " + format_number(k0_) + " N/m, fy = " + format_number(fy_) +
         " N, b = " + format_number(b_) + ")";
}

// ---------------------------------------------------------------------------------------------
BoucWen::BoucWen(double k0, double yield_drift, double alpha, double n, double beta_fraction)
    : HystereticModel(k0), uy_(yield_drift), alpha_(alpha), n_(n), beta_(0.0), gamma_(0.0) {
  require(positive_finite(k0), "BoucWen: k0 must be > 0, got " + format_number(k0));
  require(positive_finite(yield_drift),
          "BoucWen: yield drift must be > 0, got " + format_number(yield_drift));
  require(alpha >= 0.0 && alpha <= 1.0,
          "BoucWen: alpha (post-yield ratio) must be in [0, 1], got " + format_number(alpha));
  require(positive_finite(n), "BoucWen: exponent n must be > 0, got " + format_number(n));
  // beta_fraction in [0, 1] keeps gamma >= 0 and beta >= 0: a stable, softening loop whose
  // hysteretic drift z stays within +/- uy.
  require(beta_fraction >= 0.0 && beta_fraction <= 1.0,
          "BoucWen: beta fraction must be in [0, 1], got " + format_number(beta_fraction));
  const double scale = std::pow(yield_drift, n);
  beta_ = beta_fraction / scale;
  gamma_ = (1.0 - beta_fraction) / scale;
}

double BoucWen::dz_du(double z, double du) const {
  const double direction = (du * z > 0.0) ? 1.0 : (du * z < 0.0 ? -1.0 : 0.0);
  return 1.0 - std::pow(std::abs(z), n_) * (beta_ * direction + gamma_);
}

ForceState BoucWen::trial(double drift) {
  trial_.drift = drift;
  const double du = drift - committed_.drift;
  double z = committed_.internal;
  if (du != 0.0) {
    // RK4 in u with sub-steps of at most uy / 50: z changes by at most ~uy/50 per sub-step,
    // fine enough to follow the knee of the loop.
    const int substeps = std::max(1, static_cast<int>(std::ceil(std::abs(du) / (uy_ / 50.0))));
    const double h = du / substeps;
    for (int i = 0; i < substeps; ++i) {
      const double k1 = dz_du(z, du);
      const double k2 = dz_du(z + 0.5 * h * k1, du);
      const double k3 = dz_du(z + 0.5 * h * k2, du);
      const double k4 = dz_du(z + h * k3, du);
      z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
  }
  trial_.internal = z;
  const double force = alpha_ * k0_ * drift + (1.0 - alpha_) * k0_ * z;
  // The tangent continues the current loading direction; at rest (du = 0) sgn is taken as 0.
  const double tangent = alpha_ * k0_ + (1.0 - alpha_) * k0_ * dz_du(z, du);
  return {force, tangent};
}

std::unique_ptr<RestoringForceModel> BoucWen::clone() const {
  return std::make_unique<BoucWen>(*this);
}

HystereticModel::Parts BoucWen::parts() const {
  return {alpha_, uy_,
          std::make_unique<BoucWen>(1.0 / uy_, uy_, 0.0, n_, beta_ * std::pow(uy_, n_))};
}

std::string BoucWen::describe() const {
  return "bouc-wen(k0 = " + format_number(k0_) + " N/m, uy = " + format_number(uy_) +
         " m, alpha = " + format_number(alpha_) + ", n = " + format_number(n_) +
         ", beta uy^n = " + format_number(beta_ * std::pow(uy_, n_)) + ")";
}

// ---------------------------------------------------------------------------------------------
InertialSpecimen::InertialSpecimen(std::unique_ptr<RestoringForceModel> model, double mass,
                                   double damping, double period)
    : model_(std::move(model)), m_(mass), c_(damping), h_(period) {
  require(model_ != nullptr, "InertialSpecimen: a restoring-force model is needed");
  require(mass >= 0.0 && std::isfinite(mass), "InertialSpecimen: mass must be >= 0 kg");
  require(damping >= 0.0 && std::isfinite(damping), "InertialSpecimen: damping must be >= 0 N s/m");
  require(positive_finite(period), "InertialSpecimen: the sampling period must be > 0 s");
}

InertialSpecimen::InertialSpecimen(const InertialSpecimen& other)
    : model_(other.model_->clone()),
      m_(other.m_),
      c_(other.c_),
      h_(other.h_),
      x1_(other.x1_),
      x2_(other.x2_),
      trial_(other.trial_) {}

ForceState InertialSpecimen::trial(double drift) {
  trial_ = drift;
  const ForceState r = model_->trial(drift);
  const double velocity = (drift - x1_) / h_;
  const double acceleration = (drift - 2.0 * x1_ + x2_) / (h_ * h_);
  return {m_ * acceleration + c_ * velocity + r.force, r.tangent + c_ / h_ + m_ / (h_ * h_)};
}

void InertialSpecimen::commit() {
  model_->commit();
  x2_ = x1_;
  x1_ = trial_;
}

void InertialSpecimen::reset() {
  model_->reset();
  x1_ = x2_ = trial_ = 0.0;
}

std::unique_ptr<RestoringForceModel> InertialSpecimen::clone() const {
  return std::make_unique<InertialSpecimen>(*this);
}

std::string InertialSpecimen::describe() const {
  return "specimen(m = " + format_number(m_) + " kg, c = " + format_number(c_) +
         " N s/m, h = " + format_number(h_) + " s, " + model_->describe() + ")";
}

}  // namespace rths::core
