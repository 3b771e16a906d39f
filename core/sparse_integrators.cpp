#include "core/sparse_integrators.h"

#include <Eigen/SparseCholesky>

#include <stdexcept>
#include <string>

namespace rths::core {
namespace {

// s U diag(c) U^T, the model's low-rank damping (U = B, c its coefficients) scaled by s, never
// formed: a product costs 2 n m. Empty when the model has none.
class LowRank {
 public:
  LowRank(const LowRankDamping& term, double scale)
      : basis_(term.basis), scale_(scale * term.coefficients), work_(Vec::Zero(scale_.size())) {}
  bool empty() const { return scale_.size() == 0; }
  const Mat& basis() const { return basis_; }
  const Vec& scale() const { return scale_; }
  // out += sign s U diag(c) U^T x; allocates nothing.
  void add_times(const Vec& x, Vec& out, double sign = 1.0) {
    if (empty()) return;
    work_.noalias() = basis_.transpose() * x;
    work_.array() *= sign * scale_.array();
    out.noalias() += basis_ * work_;
  }

 private:
  const Mat& basis_;
  Vec scale_, work_;
};

// A symmetric positive definite matrix A + U S U^T (A sparse, U S U^T an optional low-rank term,
// S >= 0 diagonal) factorised once: A by sparse LDL^T, the rest by Woodbury's identity
//   (A + U S U^T)^-1 = A^-1 - Y W U^T A^-1,  Y = A^-1 U (n x m),  W = (I + S U^T Y)^-1 S (m x m),
// valid for a singular S. A solve costs the LDL^T's O(nnz(L)) plus 2 n m; allocates nothing.
class Factor {
 public:
  Factor(const SparseMat& a, const std::string& what) : ldlt_(a) {
    if (ldlt_.info() != Eigen::Success || !(ldlt_.vectorD().array() > 0.0).all())
      throw std::invalid_argument(what + " is not positive definite (its sparse LDL^T failed)");
    inverse_d_ = ldlt_.vectorD().cwiseInverse();
    work_ = Vec::Zero(a.rows());
  }
  Factor(const SparseMat& a, const std::string& what, const LowRank& low) : Factor(a, what) {
    if (low.empty()) return;
    const Eigen::Index m = low.scale().size();
    y_.resize(a.rows(), m);
    for (Eigen::Index i = 0; i < m; ++i) y_.col(i) = ldlt_.solve(Vec(low.basis().col(i)));
    const Mat capacitance =
        Mat::Identity(m, m) + low.scale().asDiagonal() * (low.basis().transpose() * y_);
    w_ = capacitance.partialPivLu().solve(Mat(low.scale().asDiagonal()));
    basis_ = &low.basis();
    t_ = z_ = Vec::Zero(m);
  }
  // out = (A + U S U^T)^-1 b (`out` sized, not `b`): P^T L^-T D^-1 L^-1 P b, as Eigen's solve,
  // by hand, then the Woodbury correction.
  void solve(const Vec& b, Vec& out) {
    work_.noalias() = ldlt_.permutationP() * b;
    ldlt_.matrixL().solveInPlace(work_);
    work_.array() *= inverse_d_.array();
    ldlt_.matrixU().solveInPlace(work_);
    out.noalias() = ldlt_.permutationPinv() * work_;
    if (basis_ == nullptr) return;
    t_.noalias() = basis_->transpose() * out;
    z_.noalias() = w_ * t_;
    out.noalias() -= y_ * z_;
  }

 private:
  Eigen::SimplicialLDLT<SparseMat> ldlt_;
  Vec inverse_d_, work_;
  const Mat* basis_ = nullptr;
  Mat y_, w_;
  Vec t_, z_;
};

// What every sparse scheme holds: M, C, K0 compressed, C's low-rank part, M factorised, work
// vectors sized once. C v is damping_ v plus the low-rank term (damping_low_).
class SparseExplicit : public Integrator {
 public:
  SparseExplicit(const StructuralModel& model, double dt)
      : Integrator(model, dt, false),
        mass_(model.sparse_mass),
        damping_(model.sparse_damping),
        stiffness_(model.sparse_stiffness),
        low_rank_(model.low_rank_damping),
        damping_low_(low_rank_, 1.0),
        mass_factor_(mass_, "M") {
    const int n = model.dofs();
    u_next_ = v_next_ = a_next_ = rhs_ = work_ = work2_ = Vec::Zero(n);
  }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    u_ = u0;
    v_ = v0;
    rhs_ = p0 - r0;
    subtract_damping_force(v0, rhs_);
    mass_factor_.solve(rhs_, a_);
  }

 protected:
  // out -= C v, sparse and low-rank parts.
  void subtract_damping_force(const Vec& v, Vec& out) {
    out.noalias() -= damping_ * v;
    damping_low_.add_times(v, out, -1.0);
  }
  // The low-rank part of C scaled by s, for an effective matrix's factor or product.
  LowRank low_rank(double s) const { return LowRank(low_rank_, s); }
  // a_next_ = A^-1 (p+ - r(u_next_, v_next_) - C damping_velocity), the trial committed.
  void solve_acceleration(const Vec& load_next, RestoringEvaluator& restoring,
                          const Vec& damping_velocity, Factor& effective) {
    const Vec& r = restoring.trial(u_next_, v_next_, nullptr);
    restoring.commit();
    rhs_ = load_next - r;
    subtract_damping_force(damping_velocity, rhs_);
    effective.solve(rhs_, a_next_);
  }

  SparseMat mass_, damping_, stiffness_;
  LowRankDamping low_rank_;
  LowRank damping_low_;
  Factor mass_factor_;
  Vec u_next_, v_next_, a_next_, rhs_, work_, work2_;
};

class SparseExplicitNewmark final : public SparseExplicit {
 public:
  SparseExplicitNewmark(const StructuralModel& model, double dt)
      : SparseExplicit(model, dt),
        effective_(mass_ + (0.5 * dt) * damping_, "M + dt/2 C", low_rank(0.5 * dt)) {}
  IntegratorKind kind() const override { return IntegratorKind::kExplicitNewmark; }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    u_next_ = u_ + dt_ * v_ + (0.5 * dt_ * dt_) * a_;
    v_next_ = v_ + dt_ * a_;  // predicted velocity sent with the command
    work_ = v_ + (0.5 * dt_) * a_;
    solve_acceleration(load_next, restoring, work_, effective_);
    v_ += (0.5 * dt_) * (a_ + a_next_);
    u_ = u_next_;
    a_ = a_next_;
  }

 private:
  Factor effective_;
};

class SparseCentralDifference final : public SparseExplicit {
 public:
  SparseCentralDifference(const StructuralModel& model, double dt)
      : SparseExplicit(model, dt),
        effective_(mass_ + (0.5 * dt) * damping_, "M + dt/2 C", low_rank(0.5 * dt)) {
    v_half_ = Vec::Zero(model.dofs());
  }
  IntegratorKind kind() const override { return IntegratorKind::kCentralDifference; }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    SparseExplicit::initialize(u0, v0, r0, p0);
    v_half_ = v_ - (0.5 * dt_) * a_;  // v at t = -dt/2
  }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    v_half_ += dt_ * a_;  // v_{k+1/2}
    u_next_ = u_ + dt_ * v_half_;
    v_next_ = v_half_ + (0.5 * dt_) * a_;
    solve_acceleration(load_next, restoring, v_half_, effective_);
    u_ = u_next_;
    a_ = a_next_;
    v_ = v_half_ + (0.5 * dt_) * a_;
  }

 private:
  Factor effective_;
  Vec v_half_;
};

class SparseChenRicles final : public SparseExplicit {
 public:
  SparseChenRicles(const StructuralModel& model, double dt)
      : SparseExplicit(model, dt),
        d_(4.0 * mass_ + (2.0 * dt) * damping_ + (dt * dt) * stiffness_, "4M + 2dt C + dt^2 K0",
           low_rank(2.0 * dt)) {}
  IntegratorKind kind() const override { return IntegratorKind::kChenRicles; }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    work_.noalias() = mass_ * a_;
    work_ *= 4.0;
    d_.solve(work_, work2_);  // A a = 4 D^-1 M a
    v_next_ = v_ + dt_ * work2_;
    u_next_ = u_ + dt_ * v_ + (dt_ * dt_) * work2_;
    solve_acceleration(load_next, restoring, v_next_, mass_factor_);
    u_ = u_next_;
    v_ = v_next_;
    a_ = a_next_;
  }

 private:
  Factor d_;
};

class SparseAlphaOS final : public SparseExplicit {
 public:
  SparseAlphaOS(const StructuralModel& model, double dt, double alpha, double beta, double gamma)
      : SparseExplicit(model, dt),
        alpha_(alpha),
        beta_(beta),
        gamma_(gamma),
        effective_(mass_ + (alpha * gamma * dt) * damping_ + (alpha * beta * dt * dt) * stiffness_,
                   "M + alpha gamma dt C + alpha beta dt^2 K0", low_rank(alpha * gamma * dt)) {
    predictor_ = previous_predictor_ = previous_force_ = previous_load_ = Vec::Zero(model.dofs());
  }
  IntegratorKind kind() const override { return IntegratorKind::kAlphaOS; }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    SparseExplicit::initialize(u0, v0, r0, p0);
    previous_predictor_ = u0;
    previous_force_ = r0;
    previous_load_ = p0;
  }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override;

 private:
  double alpha_, beta_, gamma_;
  Factor effective_;
  Vec predictor_, previous_predictor_, previous_force_, previous_load_;
};

void SparseAlphaOS::step(const Vec& load_next, RestoringEvaluator& restoring) {
  predictor_ = u_ + dt_ * v_ + ((0.5 - beta_) * dt_ * dt_) * a_;
  v_next_ = v_ + ((1.0 - gamma_) * dt_) * a_;
  const Vec& r = restoring.trial(predictor_, v_next_, nullptr);
  restoring.commit();
  rhs_ = (1.0 - alpha_) * previous_load_ + alpha_ * load_next;
  work_ = u_ - previous_predictor_;
  work2_.noalias() = stiffness_ * work_;  // C v + r~ + K0 (u - u~)
  damping_low_.add_times(v_, work2_);
  work2_.noalias() += damping_ * v_;
  work2_ += previous_force_;
  rhs_ -= (1.0 - alpha_) * work2_;
  work2_.noalias() = damping_ * v_next_;  // C v~+ + r~+
  damping_low_.add_times(v_next_, work2_);
  work2_ += r;
  rhs_ -= alpha_ * work2_;
  effective_.solve(rhs_, a_next_);
  u_ = predictor_ + (beta_ * dt_ * dt_) * a_next_;
  v_ = v_next_ + (gamma_ * dt_) * a_next_;
  a_ = a_next_;
  previous_predictor_ = predictor_;
  previous_force_ = r;
  previous_load_ = load_next;
}

struct KRAlphaWeights {
  double alpha_m, alpha_f, beta, gamma;
};

class SparseKRAlpha final : public SparseExplicit {
 public:
  SparseKRAlpha(const StructuralModel& model, double dt, const KRAlphaWeights& w)
      : SparseExplicit(model, dt),
        w_(w),
        s_((w.gamma * dt) * damping_ + (w.beta * dt * dt) * stiffness_),
        d_matrix_(mass_ + s_),
        b_((1.0 - w.alpha_m) * mass_ + (1.0 - w.alpha_f) * s_),
        d_low_(low_rank(w.gamma * dt)),
        b_low_(low_rank((1.0 - w.alpha_f) * w.gamma * dt)),
        d_(d_matrix_, "M + gamma dt C + beta dt^2 K0", d_low_),
        e_(w.alpha_m * mass_ + w.alpha_f * s_, "alpha_m M + alpha_f (gamma dt C + beta dt^2 K0)",
           low_rank(w.alpha_f * w.gamma * dt)) {
    previous_force_ = previous_load_ = increment_ = Vec::Zero(model.dofs());
  }
  IntegratorKind kind() const override { return IntegratorKind::kKRAlpha; }
  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    SparseExplicit::initialize(u0, v0, r0, p0);
    previous_force_ = r0;
    previous_load_ = p0;
  }
  void step(const Vec& load_next, RestoringEvaluator& restoring) override;

 private:
  KRAlphaWeights w_;
  SparseMat s_, d_matrix_, b_;  // sparse parts; with C's low-rank part scaled: D, B
  LowRank d_low_, b_low_;
  Factor d_, e_;
  Vec previous_force_, previous_load_, increment_;
};

void SparseKRAlpha::step(const Vec& load_next, RestoringEvaluator& restoring) {
  work_.noalias() = mass_ * a_;
  d_.solve(work_, increment_);
  increment_ *= dt_;  // dt A1 a, the velocity increment
  u_next_ = u_ + dt_ * v_ + ((0.5 + w_.gamma) * dt_) * increment_;
  v_next_ = v_ + increment_;
  const Vec& r = restoring.trial(u_next_, v_next_, nullptr);
  restoring.commit();
  const double keep = 1.0 - w_.alpha_f;
  rhs_ = keep * previous_load_ + w_.alpha_f * load_next;
  work_.noalias() = b_ * a_;  // M A3 a = M D^-1 B a
  b_low_.add_times(a_, work_);
  d_.solve(work_, work2_);
  rhs_.noalias() -= mass_ * work2_;
  work_ = keep * v_ + w_.alpha_f * v_next_;
  subtract_damping_force(work_, rhs_);
  rhs_ -= keep * previous_force_ + w_.alpha_f * r;
  mass_factor_.solve(rhs_, work_);  // E a+ = D M^-1 rhs
  work2_.noalias() = d_matrix_ * work_;
  d_low_.add_times(work_, work2_);
  e_.solve(work2_, a_next_);
  u_ = u_next_;
  v_ = v_next_;
  a_ = a_next_;
  previous_force_ = r;
  previous_load_ = load_next;
}

std::unique_ptr<Integrator> make_alpha_os(const StructuralModel& model, double dt, double alpha) {
  if (!(alpha >= 2.0 / 3.0 && alpha <= 1.0)) {
    throw std::invalid_argument("alpha-os: alpha_os must be in [2/3, 1], got " +
                                std::to_string(alpha));
  }
  const double beta = 0.25 * (2.0 - alpha) * (2.0 - alpha);
  return std::make_unique<SparseAlphaOS>(model, dt, alpha, beta, 1.5 - alpha);
}

std::unique_ptr<Integrator> make_kr_alpha(const StructuralModel& model, double dt, double rho) {
  if (!(rho >= 0.0 && rho <= 1.0)) {
    throw std::invalid_argument("kr-alpha: rho_infinity must be in [0, 1], got " +
                                std::to_string(rho));
  }
  const KRAlphaWeights w{(2.0 - rho) / (1.0 + rho), 1.0 / (1.0 + rho),
                         1.0 / ((1.0 + rho) * (1.0 + rho)), 0.5 * (3.0 - rho) / (1.0 + rho)};
  return std::make_unique<SparseKRAlpha>(model, dt, w);
}

}  // namespace

std::unique_ptr<Integrator> make_sparse_integrator(IntegratorKind kind,
                                                   const StructuralModel& model, double dt,
                                                   const IntegratorParameters& parameters) {
  if (!model.is_sparse()) throw std::invalid_argument("sparse integrator: the model is dense");
  switch (kind) {
    case IntegratorKind::kExplicitNewmark:
      return std::make_unique<SparseExplicitNewmark>(model, dt);
    case IntegratorKind::kCentralDifference:
      return std::make_unique<SparseCentralDifference>(model, dt);
    case IntegratorKind::kChenRicles: return std::make_unique<SparseChenRicles>(model, dt);
    case IntegratorKind::kAlphaOS: return make_alpha_os(model, dt, parameters.alpha_os);
    case IntegratorKind::kKRAlpha: return make_kr_alpha(model, dt, parameters.rho_infinity);
    case IntegratorKind::kNewmarkAverageAcceleration:
    case IntegratorKind::kExactZoh: return nullptr;
  }
  return nullptr;
}

void require_dense_scheme_fits(IntegratorKind kind, const StructuralModel& model) {
  const int n = model.dofs();
  const bool dense_held = model.mass.rows() == n;
  const std::string name =
      kind == IntegratorKind::kExactZoh ? "exact-zoh" : "newmark-average-acceleration";
  if (!model.low_rank_damping.empty())
    throw std::invalid_argument(
        name +
        " needs C as one dense matrix, and this model's modal damping is kept as factors "
        "through its lowest modes (structure.damping.modal_zeta on a model held sparse); "
        "use an explicit integrator (explicit-newmark, central-difference, chen-ricles, "
        "alpha-os, kr-alpha), or give Rayleigh damping or the matrix "
        "structure.matrices.damping");
  if (dense_held && n <= kDenseSchemeMaxDofs) return;
  const std::string why = kind == IntegratorKind::kExactZoh
                              ? "the matrix exponential of its 2n x 2n state matrix"
                              : "a dense tangent factorised every iteration";
  throw std::invalid_argument(name + " needs dense matrices (" + why +
                              "): " + (dense_held ? "" : "the model is held sparse only, ") +
                              std::to_string(n) + " DOFs against its limit of " +
                              std::to_string(kDenseSchemeMaxDofs) +
                              "; use an explicit integrator (explicit-newmark, central-difference, "
                              "chen-ricles, alpha-os, kr-alpha), which steps sparse models");
}

}  // namespace rths::core
