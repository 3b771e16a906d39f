#include "core/sparse_structure.h"

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/MatOp/SymShiftInvert.h>
#include <Spectra/SymGEigsShiftSolver.h>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace rths::core {
namespace {

// Lanczos converges to this relative accuracy; the basis is at least 20 vectors (Spectra's
// advice, ncv >= 2 nev), at most n.
constexpr double kLanczosTolerance = 1e-10;
constexpr int kLanczosIterations = 2000;

Eigen::Index basis_size(Eigen::Index n, int wanted) {
  return std::min<Eigen::Index>(n, std::max<Eigen::Index>(2 * wanted + 1, 20));
}

double infinity_norm(const SparseMat& a) {
  Vec row_sums = Vec::Zero(a.rows());
  for (Eigen::Index j = 0; j < a.outerSize(); ++j)
    for (SparseMat::InnerIterator it(a, j); it; ++it) row_sums[it.row()] += std::abs(it.value());
  return row_sums.size() > 0 ? row_sums.maxCoeff() : 0.0;
}

}  // namespace

bool prefer_sparse(Eigen::Index n, Eigen::Index nonzeros) {
  return n >= kSparseMinDofs &&
         static_cast<double>(nonzeros) <= kSparseMaxFill * static_cast<double>(n) * n;
}

void hold_sparse_if_sparse(StructuralModel& model) {
  if (model.is_sparse() && model.mass.rows() != model.dofs()) return;  // held sparse only
  const Eigen::Index n = model.mass.rows();
  const Mat pattern = model.mass.cwiseAbs() + model.damping.cwiseAbs() + model.stiffness.cwiseAbs();
  const Eigen::Index nonzeros = (pattern.array() != 0.0).count();
  if (!prefer_sparse(n, nonzeros)) {
    if (!model.low_rank_damping.empty())
      throw std::logic_error(
          "a model whose modal damping is kept as factors must stay held sparse");
    model.sparse_mass = model.sparse_damping = model.sparse_stiffness = SparseMat();
    return;
  }
  model.sparse_mass = model.mass.sparseView();
  model.sparse_damping = model.damping.sparseView();
  model.sparse_stiffness = model.stiffness.sparseView();
}

StructuralModel make_sparse_model(SparseMat mass, SparseMat damping, SparseMat stiffness,
                                  Vec influence) {
  const Eigen::Index n = mass.rows();
  if (n < 1 || mass.cols() != n || damping.rows() != n || damping.cols() != n ||
      stiffness.rows() != n || stiffness.cols() != n || influence.size() != n)
    throw std::invalid_argument("sparse model: M, C, K must be n x n and iota of length n");
  StructuralModel model;
  model.sparse_mass = std::move(mass);
  model.sparse_damping = std::move(damping);
  model.sparse_stiffness = std::move(stiffness);
  for (SparseMat* m : {&model.sparse_mass, &model.sparse_damping, &model.sparse_stiffness})
    m->makeCompressed();
  model.influence = std::move(influence);
  return model;
}

Vec mass_times(const StructuralModel& model, const Vec& x) {
  if (model.is_sparse()) return model.sparse_mass * x;
  return model.mass * x;
}

double damping_quadratic(const StructuralModel& model, const Vec& phi) {
  if (model.is_sparse()) {
    const LowRankDamping& low = model.low_rank_damping;
    const double low_part =
        low.empty() ? 0.0
                    : (low.basis.transpose() * phi).array().square().matrix().dot(low.coefficients);
    return phi.dot(model.sparse_damping * phi) + low_part;
  }
  return phi.dot(model.damping * phi);
}

Mat damping_in_modes(const StructuralModel& model, const Mat& shapes) {
  if (!model.is_sparse()) return shapes.transpose() * model.damping * shapes;
  Mat out = shapes.transpose() * (model.sparse_damping * shapes);
  const LowRankDamping& low = model.low_rank_damping;
  if (!low.empty()) {
    const Mat projected = low.basis.transpose() * shapes;  // m x q
    out += projected.transpose() * low.coefficients.asDiagonal() * projected;
  }
  return out;
}

Modes sparse_lowest_modes(const SparseMat& mass, const SparseMat& stiffness, int count) {
  const Eigen::Index n = mass.rows();
  if (count < 1 || count >= n)
    throw std::invalid_argument("sparse modes: " + std::to_string(count) +
                                " modes asked of a model of " + std::to_string(n) +
                                " DOFs (1 to n - 1)");
  // A shift just below 0 on the scale of the problem: K - sigma M is then definite even for a
  // semi-definite K, and the modes nearest it are the lowest.
  const double sigma = -1e-6 * stiffness.diagonal().cwiseAbs().maxCoeff() /
                       std::max(mass.diagonal().cwiseAbs().maxCoeff(), 1e-300);
  using ShiftInvert = Spectra::SymShiftInvert<double, Eigen::Sparse, Eigen::Sparse>;
  ShiftInvert op(stiffness, mass);
  Spectra::SparseSymMatProd<double> mass_op(mass);
  Spectra::SymGEigsShiftSolver<ShiftInvert, Spectra::SparseSymMatProd<double>,
                               Spectra::GEigsMode::ShiftInvert>
      solver(op, mass_op, count, basis_size(n, count), sigma);
  solver.init();
  solver.compute(Spectra::SortRule::LargestMagn, kLanczosIterations, kLanczosTolerance);
  if (solver.info() != Spectra::CompInfo::Successful)
    throw std::invalid_argument(
        "sparse modal analysis did not converge: M must be positive "
        "definite and K positive semi-definite");
  const Vec lambda = solver.eigenvalues();
  const Mat vectors = solver.eigenvectors();
  std::vector<Eigen::Index> order(static_cast<std::size_t>(lambda.size()));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::sort(order.begin(), order.end(),
            [&](Eigen::Index a, Eigen::Index b) { return lambda[a] < lambda[b]; });
  Modes modes;
  modes.omega.resize(count);
  modes.shapes.resize(n, count);
  for (int i = 0; i < count; ++i) {
    const Eigen::Index k = order[static_cast<std::size_t>(i)];
    modes.omega[i] = std::sqrt(std::max(lambda[k], 0.0));
    const Vec phi = vectors.col(k);
    modes.shapes.col(i) = phi / std::sqrt(phi.dot(mass * phi));  // Phi^T M Phi = I
  }
  return modes;
}

Modes lowest_modes(const StructuralModel& model, int count) {
  if (model.is_sparse() && count < model.dofs())
    return sparse_lowest_modes(model.sparse_mass, model.sparse_stiffness, count);
  if (model.mass.rows() != model.dofs())
    throw std::invalid_argument("modal analysis: all " + std::to_string(model.dofs()) +
                                " modes of a model held sparse only need a dense problem");
  return modal_analysis(model.mass, model.stiffness);
}

std::optional<std::string> check_sparse_definite(const SparseMat& a, bool strictly) {
  const double scale = infinity_norm(a);
  const double s = 1e-9 * scale;
  SparseMat shifted = a;
  for (Eigen::Index i = 0; i < a.rows(); ++i) shifted.coeffRef(i, i) += strictly ? -s : s;
  const Eigen::SimplicialLDLT<SparseMat> ldlt(shifted);
  const bool ok = ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > 0.0).all();
  if (ok) return std::nullopt;
  std::ostringstream why;
  why << "is not positive " << (strictly ? "definite" : "semi-definite")
      << ": its LDL^T shifted by " << (strictly ? "-" : "+") << s
      << " (1e-9 of its largest row sum " << scale << ") has a pivot <= 0";
  return why.str();
}

void sparse_rayleigh_damping(StructuralModel& model, double zeta, int mode_i, int mode_j) {
  const int n = model.dofs();
  if (mode_i < 1 || mode_j < 1 || mode_i > n || mode_j > n || mode_i == mode_j) {
    throw std::invalid_argument("Rayleigh damping: modes " + std::to_string(mode_i) + " and " +
                                std::to_string(mode_j) + " must be distinct and in 1.." +
                                std::to_string(n));
  }
  const Modes modes = lowest_modes(model, std::max(mode_i, mode_j));
  const double wi = modes.omega(mode_i - 1), wj = modes.omega(mode_j - 1);
  // zeta = a0 / (2 w) + a1 w / 2 at both frequencies (as core::rayleigh_damping).
  const double a0 = 2.0 * zeta * wi * wj / (wi + wj);
  const double a1 = 2.0 * zeta / (wi + wj);
  model.sparse_damping = a0 * model.sparse_mass + a1 * model.sparse_stiffness;
  if (model.mass.rows() == n) model.damping = a0 * model.mass + a1 * model.stiffness;
}

namespace {

// The share of iota^T M iota that modes 1..m hold, (sum_i (phi_i^T M iota)^2) / iota^T M iota.
double mass_share(const Modes& modes, int m, const Vec& mass_iota, double total) {
  return (modes.shapes.leftCols(m).transpose() * mass_iota).squaredNorm() / total;
}

std::string modal_text(const SparseModalDamping& d, double zeta, int n) {
  std::ostringstream out;
  out << std::setprecision(3) << "structure.damping.modal_zeta on " << n
      << " DOFs held sparse: zeta " << zeta << " in the lowest " << d.modes << " modes (up to "
      << d.omega_kept / (2.0 * std::numbers::pi) << " Hz, " << 100.0 * d.mass_share
      << " % of the mass along iota), kept as a rank-" << d.modes
      << " term; the higher modes get stiffness-proportional damping " << d.stiffness_factor
      << " K (zeta " << zeta << " at mode " << d.modes + 1 << ", "
      << d.omega_next / (2.0 * std::numbers::pi)
      << " Hz, growing with frequency); C is never formed dense";
  return out.str();
}

}  // namespace

SparseModalDamping sparse_modal_damping(StructuralModel& model, double zeta) {
  const int n = model.dofs();
  if (!model.is_sparse())
    throw std::invalid_argument("structure.damping.modal_zeta: the model is not held sparse");
  if (!(zeta > 0.0 && zeta <= 1.0))
    throw std::invalid_argument("structure.damping.modal_zeta: " + std::to_string(zeta) +
                                " must be in (0, 1]");
  const int most = std::min(kModalMaxModes, n - 2);
  const Vec mass_iota = model.sparse_mass * model.influence;
  const double total = model.influence.dot(mass_iota);
  SparseModalDamping d;
  Modes modes;
  for (int m = std::min(kModalMinModes, most);; m = std::min(2 * m, most)) {
    try {
      modes = sparse_lowest_modes(model.sparse_mass, model.sparse_stiffness, m + 1);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(
          "structure.damping.modal_zeta: the lowest " + std::to_string(m + 1) +
          " modes could not be found (" + e.what() +
          "); give Rayleigh damping (damping { rayleigh { zeta: ... } }) or the matrix "
          "structure.matrices.damping instead");
    }
    d.modes = m;
    d.mass_share = total > 0 ? mass_share(modes, m, mass_iota, total) : 1.0;
    if (d.mass_share >= kModalMassShare || m == most) break;
  }
  const int m = d.modes;
  d.omega_kept = modes.omega[m - 1];
  d.omega_next = modes.omega[m];
  d.stiffness_factor = 2.0 * zeta / d.omega_next;
  const Vec omega = modes.omega.head(m);
  LowRankDamping& low = model.low_rank_damping;
  low.basis = model.sparse_mass * modes.shapes.leftCols(m);
  low.coefficients =
      (2.0 * zeta * omega.array() - d.stiffness_factor * omega.array().square()).max(0.0);
  model.sparse_damping = d.stiffness_factor * model.sparse_stiffness;
  if (model.mass.rows() == n) model.damping = d.stiffness_factor * model.stiffness;
  d.text = modal_text(d, zeta, n);
  low.statement = d.text;
  return d;
}

}  // namespace rths::core
