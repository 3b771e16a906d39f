#include "core/integrators.h"

#include "core/exact_zoh.h"
#include "core/explicit_schemes.h"
#include "core/sparse_integrators.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rths::core {

namespace schemes = explicit_schemes;

std::string to_string(IntegratorKind kind) {
  switch (kind) {
    case IntegratorKind::kExplicitNewmark: return "explicit-newmark";
    case IntegratorKind::kCentralDifference: return "central-difference";
    case IntegratorKind::kChenRicles: return "chen-ricles";
    case IntegratorKind::kNewmarkAverageAcceleration: return "newmark-average-acceleration";
    case IntegratorKind::kAlphaOS: return "alpha-os";
    case IntegratorKind::kKRAlpha: return "kr-alpha";
    case IntegratorKind::kExactZoh: return "exact-zoh";
  }
  return "unknown";
}

IntegratorKind integrator_from_string(const std::string& name) {
  if (name == "explicit-newmark" || name == "newmark-explicit")
    return IntegratorKind::kExplicitNewmark;
  if (name == "central-difference" || name == "cd") return IntegratorKind::kCentralDifference;
  if (name == "chen-ricles" || name == "cr") return IntegratorKind::kChenRicles;
  if (name == "newmark-average-acceleration" || name == "implicit-newmark" ||
      name == "average-acceleration") {
    return IntegratorKind::kNewmarkAverageAcceleration;
  }
  if (name == "alpha-os" || name == "alphaos") return IntegratorKind::kAlphaOS;
  if (name == "kr-alpha" || name == "kralpha") return IntegratorKind::kKRAlpha;
  if (name == "exact-zoh" || name == "zoh") return IntegratorKind::kExactZoh;
  throw std::invalid_argument("unknown integrator '" + name +
                              "': expected explicit-newmark, central-difference, chen-ricles, "
                              "newmark-average-acceleration, alpha-os, kr-alpha or exact-zoh");
}

double stability_limit(IntegratorKind kind) {
  switch (kind) {
    case IntegratorKind::kExplicitNewmark:
    case IntegratorKind::kCentralDifference: return 2.0;
    case IntegratorKind::kChenRicles:
    case IntegratorKind::kNewmarkAverageAcceleration:
    case IntegratorKind::kAlphaOS:
    case IntegratorKind::kKRAlpha:
    case IntegratorKind::kExactZoh: return std::numeric_limits<double>::infinity();
  }
  return 0.0;
}

bool is_explicit(IntegratorKind kind) {
  return kind != IntegratorKind::kNewmarkAverageAcceleration;
}

void check_stability(IntegratorKind kind, double omega_max, double dt, bool allow_unstable) {
  if (!(dt > 0)) throw std::invalid_argument("time step dt must be > 0 s");
  const double limit = stability_limit(kind);
  if (omega_max * dt > limit && !allow_unstable) {
    std::ostringstream msg;
    msg << to_string(kind) << " is unstable for omega_max * dt = " << omega_max * dt << " > "
        << limit << " (omega_max = " << omega_max << " rad/s, dt = " << dt
        << " s); use dt <= " << limit / omega_max << " s, another integrator, or allow_unstable";
    throw std::invalid_argument(msg.str());
  }
}

namespace {

// The explicit schemes' linear algebra on dense M, C, K0 (core/explicit_schemes.h): each matrix
// formed once, each effective matrix inverted once, so a product or a solve is one dense
// matrix-vector product (no allocation).
class DenseAlgebra {
 public:
  explicit DenseAlgebra(const StructuralModel& model)
      : mass_(model.mass), damping_(model.damping), stiffness_(model.stiffness) {}

  class Product {
   public:
    explicit Product(Mat matrix) : matrix_(std::move(matrix)) {}
    void add_times(const Vec& x, Vec& out, double sign) const {
      if (sign > 0)
        out.noalias() += matrix_ * x;
      else
        out.noalias() -= matrix_ * x;
    }

   private:
    Mat matrix_;
  };
  class Solve {
   public:
    explicit Solve(const Mat& matrix) : inverse_(matrix.inverse()) {}
    void solve(const Vec& b, Vec& out) const { out.noalias() = inverse_ * b; }
    void solve_minus_damping(Vec& b, const Product& damping, const Vec& x, Vec& out) const {
      damping.add_times(x, b, -1.0);
      solve(b, out);
    }

   private:
    Mat inverse_;
  };

  Product product(double m, double c, double k) const { return Product(combination(m, c, k)); }
  Solve solve(double m, double c, double k, const char* /*what*/) const {
    return Solve(combination(m, c, k));
  }

 private:
  Mat combination(double m, double c, double k) const {
    return m * mass_ + c * damping_ + k * stiffness_;
  }
  Mat mass_, damping_, stiffness_;
};

// Newton iteration on u_{k+1} with a_{k+1} = 4/dt^2 (u+ - u - dt v) - a and
// v_{k+1} = v + dt/2 (a + a+); tangent 4/dt^2 M + 2/dt C + K_t.
class NewmarkAverageAcceleration final : public Integrator {
 public:
  NewmarkAverageAcceleration(const StructuralModel& model, double dt) : Integrator(model, dt) {}
  IntegratorKind kind() const override { return IntegratorKind::kNewmarkAverageAcceleration; }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    u_ = u0;
    v_ = v0;
    a_ = m_.ldlt().solve(p0 - c_ * v0 - r0);
  }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    if (!restoring.repeatable()) {
      throw std::invalid_argument(
          "newmark-average-acceleration is implicit and iterates on the restoring force; a "
          "delayed or remote experimental substructure cannot be evaluated twice per step. Use "
          "it for reference runs only, or choose an explicit integrator");
    }
    const double c1 = 4.0 / (dt_ * dt_), c2 = 2.0 / dt_;
    Vec u_next = u_ + dt_ * v_ + (0.25 * dt_ * dt_) * a_;
    Mat tangent(u_.size(), u_.size());
    Vec a_next, v_next;
    const double scale = std::max(1.0, u_next.cwiseAbs().maxCoeff());
    for (int iteration = 0;; ++iteration) {
      a_next = c1 * (u_next - u_ - dt_ * v_) - a_;
      v_next = v_ + (0.5 * dt_) * (a_ + a_next);
      const Vec& r = restoring.trial(u_next, v_next, &tangent);
      const Vec residual = load_next - m_ * a_next - c_ * v_next - r;
      const Mat effective = c1 * m_ + c2 * c_ + tangent;
      const Vec du = effective.ldlt().solve(residual);
      u_next += du;
      if (du.cwiseAbs().maxCoeff() <= 1e-13 * scale) break;
      if (iteration == 50) {
        throw std::runtime_error(
            "newmark-average-acceleration: Newton did not converge in 50 "
            "iterations");
      }
    }
    a_next = c1 * (u_next - u_ - dt_ * v_) - a_;
    v_next = v_ + (0.5 * dt_) * (a_ + a_next);
    restoring.trial(u_next, v_next, nullptr);
    restoring.commit();
    u_ = u_next;
    v_ = v_next;
    a_ = a_next;
  }
};

}  // namespace

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const StructuralModel& model,
                                            double dt) {
  return make_integrator(kind, model, dt, IntegratorParameters{});
}

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const StructuralModel& model,
                                            double dt, const IntegratorParameters& parameters) {
  if (model.is_sparse()) {
    if (auto sparse = make_sparse_integrator(kind, model, dt, parameters)) return sparse;
    require_dense_scheme_fits(kind, model);
  }
  switch (kind) {
    case IntegratorKind::kAlphaOS:
      return std::make_unique<schemes::AlphaOS<DenseAlgebra>>(model, dt, parameters.alpha_os);
    case IntegratorKind::kKRAlpha:
      return std::make_unique<schemes::KRAlpha<DenseAlgebra>>(model, dt, parameters.rho_infinity);
    case IntegratorKind::kExplicitNewmark:
      return std::make_unique<schemes::ExplicitNewmark<DenseAlgebra>>(model, dt);
    case IntegratorKind::kCentralDifference:
      return std::make_unique<schemes::CentralDifference<DenseAlgebra>>(model, dt);
    case IntegratorKind::kChenRicles:
      return std::make_unique<schemes::ChenRicles<DenseAlgebra>>(model, dt);
    case IntegratorKind::kNewmarkAverageAcceleration:
      return std::make_unique<NewmarkAverageAcceleration>(model, dt);
    case IntegratorKind::kExactZoh:
      return make_exact_zoh_integrator(
          model, dt,
          parameters.exact_stiffness.size() > 0 ? parameters.exact_stiffness : model.stiffness);
  }
  throw std::invalid_argument("unknown integrator kind");
}

}  // namespace rths::core
