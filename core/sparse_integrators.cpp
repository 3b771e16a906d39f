#include "core/sparse_integrators.h"

#include <Eigen/SparseCholesky>

#include "core/explicit_schemes.h"

#include <stdexcept>
#include <string>

namespace rths::core {
namespace {

namespace schemes = explicit_schemes;

// s U diag(c) U^T, the model's low-rank damping (U = B, c its coefficients) scaled by s, never
// formed: a product costs 2 n m. Empty when the model has none or s is 0.
class LowRank {
 public:
  LowRank(const LowRankDamping& term, double scale)
      : basis_(term.basis),
        scale_(scale == 0.0 ? Vec() : Vec(scale * term.coefficients)),
        work_(Vec::Zero(scale_.size())) {}
  bool empty() const { return scale_.size() == 0; }
  const Mat& basis() const { return basis_; }
  const Vec& scale() const { return scale_; }
  // out += sign s U diag(c) U^T x; allocates nothing.
  void add_times(const Vec& x, Vec& out, double sign = 1.0) {
    if (empty()) return;
    out.noalias() += basis_ * projection(x, sign);
  }
  // sign s diag(c) U^T x (m entries), held until the next call; allocates nothing.
  const Vec& projection(const Vec& x, double sign = 1.0) {
    work_.noalias() = basis_.transpose() * x;
    work_.array() *= sign * scale_.array();
    return work_;
  }

 private:
  const Mat& basis_;
  Vec scale_, work_;
};

// x -> out += sign (A + U S U^T) x: A sparse, U S U^T an optional low-rank term (LowRank).
class SparseProduct {
 public:
  SparseProduct(SparseMat matrix, LowRank low) : matrix_(std::move(matrix)), low_(std::move(low)) {}
  void add_times(const Vec& x, Vec& out, double sign) {
    add_sparse_times(x, out, sign);
    low_.add_times(x, out, sign);
  }
  void add_sparse_times(const Vec& x, Vec& out, double sign) const {
    if (sign > 0)
      out.noalias() += matrix_ * x;
    else
      out.noalias() -= matrix_ * x;
  }
  LowRank& low() { return low_; }

 private:
  SparseMat matrix_;
  LowRank low_;
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
    basis_ttimes_y_ = low.basis().transpose() * y_;
    basis_ = &low.basis();
    t_ = z_ = Vec::Zero(m);
  }
  // out = (A + U S U^T)^-1 b (`out` sized, not `b`): P^T L^-T D^-1 L^-1 P b, as Eigen's solve,
  // by hand, then the Woodbury correction.
  void solve(const Vec& b, Vec& out) {
    solve_sparse(b, out);
    if (basis_ == nullptr) return;
    t_.noalias() = basis_->transpose() * out;
    z_.noalias() = w_ * t_;
    out.noalias() -= y_ * z_;
  }
  // out = (A + U S U^T)^-1 (b - C x), C = `damping`: C_s + U S_d U^T on the same U (b is
  // overwritten). With g = A^-1 (b - C_s x) and s = S_d U^T x:
  //   out = g - Y (s + W t),  t = U^T g - (U^T Y) s,
  // 3 n m for the low-rank terms where the product then the solve took 4 n m.
  void solve_minus_damping(Vec& b, SparseProduct& damping, const Vec& x, Vec& out) {
    if (basis_ == nullptr || damping.low().empty()) {
      damping.add_times(x, b, -1.0);
      solve(b, out);
      return;
    }
    damping.add_sparse_times(x, b, -1.0);
    const Vec& s = damping.low().projection(x);
    solve_sparse(b, out);
    t_.noalias() = basis_->transpose() * out;
    t_.noalias() -= basis_ttimes_y_ * s;
    z_ = s;
    z_.noalias() += w_ * t_;
    out.noalias() -= y_ * z_;
  }

 private:
  // out = A^-1 b: P^T L^-T D^-1 L^-1 P b, as Eigen's solve, by hand.
  void solve_sparse(const Vec& b, Vec& out) {
    work_.noalias() = ldlt_.permutationP() * b;
    ldlt_.matrixL().solveInPlace(work_);
    work_.array() *= inverse_d_.array();
    ldlt_.matrixU().solveInPlace(work_);
    out.noalias() = ldlt_.permutationPinv() * work_;
  }

  Eigen::SimplicialLDLT<SparseMat> ldlt_;
  Vec inverse_d_, work_;
  const Mat* basis_ = nullptr;
  Mat y_, w_, basis_ttimes_y_;  // basis_ttimes_y_: U^T Y, m x m
  Vec t_, z_;
};

// The explicit schemes' linear algebra on a model held sparse (core/explicit_schemes.h):
// m M + c C + k K0 compressed once, with C's low-rank part scaled by c; each effective matrix
// factorised once (Factor). Products cost O(nnz + n m), solves O(nnz(L) + n m); no allocation.
class SparseAlgebra {
 public:
  explicit SparseAlgebra(const StructuralModel& model)
      : mass_(model.sparse_mass),
        damping_(model.sparse_damping),
        stiffness_(model.sparse_stiffness),
        low_rank_(model.low_rank_damping) {}

  using Product = SparseProduct;
  using Solve = Factor;

  Product product(double m, double c, double k) const {
    return Product(combination(m, c, k), LowRank(low_rank_, c));
  }
  Solve solve(double m, double c, double k, const char* what) const {
    return Factor(combination(m, c, k), what, LowRank(low_rank_, c));
  }

 private:
  SparseMat combination(double m, double c, double k) const {
    return m * mass_ + c * damping_ + k * stiffness_;
  }
  SparseMat mass_, damping_, stiffness_;
  LowRankDamping low_rank_;
};

}  // namespace

std::unique_ptr<Integrator> make_sparse_integrator(IntegratorKind kind,
                                                   const StructuralModel& model, double dt,
                                                   const IntegratorParameters& parameters) {
  if (!model.is_sparse()) throw std::invalid_argument("sparse integrator: the model is dense");
  switch (kind) {
    case IntegratorKind::kExplicitNewmark:
      return std::make_unique<schemes::ExplicitNewmark<SparseAlgebra>>(model, dt);
    case IntegratorKind::kCentralDifference:
      return std::make_unique<schemes::CentralDifference<SparseAlgebra>>(model, dt);
    case IntegratorKind::kChenRicles:
      return std::make_unique<schemes::ChenRicles<SparseAlgebra>>(model, dt);
    case IntegratorKind::kAlphaOS:
      return std::make_unique<schemes::AlphaOS<SparseAlgebra>>(model, dt, parameters.alpha_os);
    case IntegratorKind::kKRAlpha:
      return std::make_unique<schemes::KRAlpha<SparseAlgebra>>(model, dt, parameters.rho_infinity);
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
