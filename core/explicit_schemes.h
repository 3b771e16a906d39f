#pragma once
// The explicit schemes of core/integrators.h, each recurrence written once, on the linear algebra
// of its model as a parameter: DenseAlgebra (core/integrators.cpp: M, C, K0 dense, each
// effective matrix inverted once) or SparseAlgebra (core/sparse_integrators.cpp: compressed
// matrices and C's low-rank part, each effective matrix factorised once by LDL^T).
//
// An Algebra supplies, for coefficients (m, c, k) of the matrix m M + c C + k K0:
//   Algebra(model)                        built once from the model
//   Product product(m, c, k)              x -> out += sign (m M + c C + k K0) x, sign +1 or -1
//                                         (Product::add_times(x, out, sign))
//   Solve solve(m, c, k, what)            b -> out = (m M + c C + k K0)^-1 b
//                                         (Solve::solve(b, out); `what` names the matrix when it
//                                         cannot be factorised: std::invalid_argument)
//   Solve::solve_minus_damping(b, damping, x, out)
//                                         out = (m M + c C + k K0)^-1 (b - C x), `damping` the
//                                         product(0, 1, 0); b is overwritten
// and neither add_times nor solve allocates. Units SI: m, m/s, m/s^2, N, s. Every scheme sizes
// its work vectors once, so step() does not allocate (real-time safe).

#include <stdexcept>
#include <string>

#include "core/integrator.h"

namespace rths::core::explicit_schemes {

// Throws std::invalid_argument naming alpha_os and its range [2/3, 1].
inline double checked_alpha_os(double alpha) {
  if (!(alpha >= 2.0 / 3.0 && alpha <= 1.0))
    throw std::invalid_argument("alpha-os: alpha_os must be in [2/3, 1], got " +
                                std::to_string(alpha));
  return alpha;
}

// What every scheme holds: the damping product, the mass solve, work vectors.
template <class Algebra>
class Base : public Integrator {
 public:
  Base(const StructuralModel& model, double dt)
      : Integrator(model, dt, false),
        algebra_(model),
        damping_(algebra_.product(0.0, 1.0, 0.0)),
        mass_solve_(algebra_.solve(1.0, 0.0, 0.0, "M")) {
    u_next_ = v_next_ = a_next_ = rhs_ = work_ = work2_ = Vec::Zero(model.dofs());
  }
  // a0 from equilibrium M a0 = p0 - C v0 - r0.
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    u_ = u0;
    v_ = v0;
    rhs_ = p0 - r0;
    damping_.add_times(v0, rhs_, -1.0);
    mass_solve_.solve(rhs_, a_);
  }

 protected:
  // a_next_ = A^-1 (p+ - r(u_next_, v_next_) - C damping_velocity), the trial committed.
  void solve_acceleration(const Vec& load_next, RestoringEvaluator& restoring,
                          const Vec& damping_velocity, typename Algebra::Solve& effective) {
    const Vec& r = restoring.trial(u_next_, v_next_, nullptr);
    restoring.commit();
    rhs_ = load_next - r;
    effective.solve_minus_damping(rhs_, damping_, damping_velocity, a_next_);
  }

  Algebra algebra_;
  typename Algebra::Product damping_;
  typename Algebra::Solve mass_solve_;
  Vec u_next_, v_next_, a_next_, rhs_, work_, work2_;
};

// (M + dt/2 C) a+ = p+ - r+ - C (v + dt/2 a);  v+ = v + dt/2 (a + a+).
template <class Algebra>
class ExplicitNewmark final : public Base<Algebra> {
  using B = Base<Algebra>;

 public:
  ExplicitNewmark(const StructuralModel& model, double dt)
      : B(model, dt), effective_(this->algebra_.solve(1.0, 0.5 * dt, 0.0, "M + dt/2 C")) {}
  IntegratorKind kind() const override { return IntegratorKind::kExplicitNewmark; }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    const double dt = this->dt_;
    this->u_next_ = this->u_ + dt * this->v_ + (0.5 * dt * dt) * this->a_;
    this->v_next_ = this->v_ + dt * this->a_;  // predicted velocity sent with the command
    this->work_ = this->v_ + (0.5 * dt) * this->a_;
    this->solve_acceleration(load_next, restoring, this->work_, effective_);
    this->v_ += (0.5 * dt) * (this->a_ + this->a_next_);
    this->u_ = this->u_next_;
    this->a_ = this->a_next_;
  }

 private:
  typename Algebra::Solve effective_;
};

// v_{k+1/2} = v_{k-1/2} + dt a_k;  u+ = u + dt v_{k+1/2};  equilibrium at k+1 with
// v+ = v_{k+1/2} + dt/2 a+, so (M + dt/2 C) a+ = p+ - r+ - C v_{k+1/2}.
template <class Algebra>
class CentralDifference final : public Base<Algebra> {
  using B = Base<Algebra>;

 public:
  CentralDifference(const StructuralModel& model, double dt)
      : B(model, dt), effective_(this->algebra_.solve(1.0, 0.5 * dt, 0.0, "M + dt/2 C")) {
    v_half_ = Vec::Zero(model.dofs());
  }
  IntegratorKind kind() const override { return IntegratorKind::kCentralDifference; }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    B::initialize(u0, v0, r0, p0);
    v_half_ = this->v_ - (0.5 * this->dt_) * this->a_;  // v at t = -dt/2
  }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    const double dt = this->dt_;
    v_half_ += dt * this->a_;  // v_{k+1/2}
    this->u_next_ = this->u_ + dt * v_half_;
    this->v_next_ = v_half_ + (0.5 * dt) * this->a_;
    this->solve_acceleration(load_next, restoring, v_half_, effective_);
    this->u_ = this->u_next_;
    this->a_ = this->a_next_;
    this->v_ = v_half_ + (0.5 * dt) * this->a_;
  }

 private:
  typename Algebra::Solve effective_;
  Vec v_half_;
};

// A a = 4 (4M + 2dt C + dt^2 K0)^-1 (M a);  v+ = v + dt A a;  u+ = u + dt v + dt^2 A a;
// M a+ = p+ - C v+ - r+.
template <class Algebra>
class ChenRicles final : public Base<Algebra> {
  using B = Base<Algebra>;

 public:
  ChenRicles(const StructuralModel& model, double dt)
      : B(model, dt),
        four_mass_(this->algebra_.product(4.0, 0.0, 0.0)),
        d_(this->algebra_.solve(4.0, 2.0 * dt, dt * dt, "4M + 2dt C + dt^2 K0")) {}
  IntegratorKind kind() const override { return IntegratorKind::kChenRicles; }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    const double dt = this->dt_;
    this->work_.setZero();
    four_mass_.add_times(this->a_, this->work_, 1.0);
    d_.solve(this->work_, this->work2_);  // A a
    this->v_next_ = this->v_ + dt * this->work2_;
    this->u_next_ = this->u_ + dt * this->v_ + (dt * dt) * this->work2_;
    this->solve_acceleration(load_next, restoring, this->v_next_, this->mass_solve_);
    this->u_ = this->u_next_;
    this->v_ = this->v_next_;
    this->a_ = this->a_next_;
  }

 private:
  typename Algebra::Product four_mass_;
  typename Algebra::Solve d_;
};

// Alpha-operator splitting, alpha in [2/3, 1], beta = (2 - alpha)^2 / 4,
// gamma = 3/2 - alpha: the equations of core/integrators.h ALPHA_OS.
template <class Algebra>
class AlphaOS final : public Base<Algebra> {
  using B = Base<Algebra>;

 public:
  AlphaOS(const StructuralModel& model, double dt, double alpha)
      : B(model, dt),
        alpha_(checked_alpha_os(alpha)),
        beta_(0.25 * (2.0 - alpha) * (2.0 - alpha)),
        gamma_(1.5 - alpha),
        stiffness_(this->algebra_.product(0.0, 0.0, 1.0)),
        effective_(this->algebra_.solve(1.0, alpha * gamma_ * dt, alpha * beta_ * dt * dt,
                                        "M + alpha gamma dt C + alpha beta dt^2 K0")) {
    predictor_ = previous_predictor_ = previous_force_ = previous_load_ = Vec::Zero(model.dofs());
  }
  IntegratorKind kind() const override { return IntegratorKind::kAlphaOS; }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    B::initialize(u0, v0, r0, p0);
    previous_predictor_ = u0;
    previous_force_ = r0;
    previous_load_ = p0;
  }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override;

 private:
  double alpha_, beta_, gamma_;
  typename Algebra::Product stiffness_;
  typename Algebra::Solve effective_;
  Vec predictor_, previous_predictor_, previous_force_, previous_load_;
};

template <class Algebra>
void AlphaOS<Algebra>::step(const Vec& load_next, RestoringEvaluator& restoring) {
  const double dt = this->dt_;
  Vec &work = this->work_, &work2 = this->work2_, &rhs = this->rhs_;
  predictor_ = this->u_ + dt * this->v_ + ((0.5 - beta_) * dt * dt) * this->a_;
  this->v_next_ = this->v_ + ((1.0 - gamma_) * dt) * this->a_;
  const Vec& r = restoring.trial(predictor_, this->v_next_, nullptr);
  restoring.commit();
  rhs = (1.0 - alpha_) * previous_load_ + alpha_ * load_next;
  work = this->u_ - previous_predictor_;
  work2 = previous_force_;  // C v + r~ + K0 (u - u~)
  stiffness_.add_times(work, work2, 1.0);
  this->damping_.add_times(this->v_, work2, 1.0);
  rhs -= (1.0 - alpha_) * work2;
  work2 = r;  // C v~+ + r~+
  this->damping_.add_times(this->v_next_, work2, 1.0);
  rhs -= alpha_ * work2;
  effective_.solve(rhs, this->a_next_);
  this->u_ = predictor_ + (beta_ * dt * dt) * this->a_next_;
  this->v_ = this->v_next_ + (gamma_ * dt) * this->a_next_;
  this->a_ = this->a_next_;
  previous_predictor_ = predictor_;
  previous_force_ = r;
  previous_load_ = load_next;
}

// KR-alpha's weights from rho_inf (core/integrators.h KR_ALPHA). Throws std::invalid_argument
// naming rho_infinity and its range [0, 1].
struct KRAlphaWeights {
  double alpha_m, alpha_f, beta, gamma;
  static KRAlphaWeights of(double rho) {
    if (!(rho >= 0.0 && rho <= 1.0))
      throw std::invalid_argument("kr-alpha: rho_infinity must be in [0, 1], got " +
                                  std::to_string(rho));
    return {(2.0 - rho) / (1.0 + rho), 1.0 / (1.0 + rho), 1.0 / ((1.0 + rho) * (1.0 + rho)),
            0.5 * (3.0 - rho) / (1.0 + rho)};
  }
};

// KR-alpha with D = M + S, S = gamma dt C + beta dt^2 K0, B = (1 - alpha_m) M + (1 - alpha_f) S,
// E = alpha_m M + alpha_f S (= D - B): A1 a = D^-1 (M a), M A3 a = M D^-1 (B a), and
// M^ = M (I - A3) = M D^-1 E, so M^ a+ = f solves as E a+ = D (M^-1 f). At rho_inf = 1 it is
// only marginally stable for omega dt >> 1 (measured: 1.4x growth over 2000 steps at
// omega dt = 1000); rho_inf < 1 damps those modes.
template <class Algebra>
class KRAlpha final : public Base<Algebra> {
  using B = Base<Algebra>;

 public:
  KRAlpha(const StructuralModel& model, double dt, double rho_infinity)
      : KRAlpha(model, dt, KRAlphaWeights::of(rho_infinity)) {}
  KRAlpha(const StructuralModel& model, double dt, const KRAlphaWeights& w)
      : B(model, dt),
        w_(w),
        mass_(this->algebra_.product(1.0, 0.0, 0.0)),
        d_product_(this->algebra_.product(1.0, w.gamma * dt, w.beta * dt * dt)),
        b_product_(this->algebra_.product(1.0 - w.alpha_m, (1.0 - w.alpha_f) * w.gamma * dt,
                                          (1.0 - w.alpha_f) * w.beta * dt * dt)),
        d_(this->algebra_.solve(1.0, w.gamma * dt, w.beta * dt * dt,
                                "M + gamma dt C + beta dt^2 K0")),
        e_(this->algebra_.solve(w.alpha_m, w.alpha_f * w.gamma * dt, w.alpha_f * w.beta * dt * dt,
                                "alpha_m M + alpha_f (gamma dt C + beta dt^2 K0)")) {
    previous_force_ = previous_load_ = increment_ = Vec::Zero(model.dofs());
  }
  IntegratorKind kind() const override { return IntegratorKind::kKRAlpha; }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    B::initialize(u0, v0, r0, p0);
    previous_force_ = r0;
    previous_load_ = p0;
  }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override;

 private:
  KRAlphaWeights w_;
  typename Algebra::Product mass_, d_product_, b_product_;
  typename Algebra::Solve d_, e_;
  Vec previous_force_, previous_load_, increment_;
};

template <class Algebra>
void KRAlpha<Algebra>::step(const Vec& load_next, RestoringEvaluator& restoring) {
  const double dt = this->dt_;
  Vec &work = this->work_, &work2 = this->work2_, &rhs = this->rhs_;
  work.setZero();
  mass_.add_times(this->a_, work, 1.0);
  d_.solve(work, increment_);
  increment_ *= dt;  // dt A1 a, the velocity increment
  this->u_next_ = this->u_ + dt * this->v_ + ((0.5 + w_.gamma) * dt) * increment_;
  this->v_next_ = this->v_ + increment_;
  const Vec& r = restoring.trial(this->u_next_, this->v_next_, nullptr);
  restoring.commit();
  const double keep = 1.0 - w_.alpha_f;
  rhs = keep * previous_load_ + w_.alpha_f * load_next;
  work.setZero();
  b_product_.add_times(this->a_, work, 1.0);  // M A3 a = M D^-1 B a
  d_.solve(work, work2);
  mass_.add_times(work2, rhs, -1.0);
  work = keep * this->v_ + w_.alpha_f * this->v_next_;
  this->damping_.add_times(work, rhs, -1.0);
  rhs -= keep * previous_force_ + w_.alpha_f * r;
  this->mass_solve_.solve(rhs, work);  // E a+ = D M^-1 rhs
  work2.setZero();
  d_product_.add_times(work, work2, 1.0);
  e_.solve(work2, this->a_next_);
  this->u_ = this->u_next_;
  this->v_ = this->v_next_;
  this->a_ = this->a_next_;
  previous_force_ = r;
  previous_load_ = load_next;
}

}  // namespace rths::core::explicit_schemes
