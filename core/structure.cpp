#include "core/structure.h"

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rths::core {

StructuralModel make_shear_building(const std::vector<double>& storey_mass,
                                    const std::vector<double>& storey_stiffness) {
  if (storey_mass.empty()) throw std::invalid_argument("shear building: no storey masses");
  if (storey_mass.size() != storey_stiffness.size()) {
    throw std::invalid_argument("shear building: " + std::to_string(storey_mass.size()) +
                                " storey masses but " + std::to_string(storey_stiffness.size()) +
                                " storey stiffnesses");
  }
  const int n = static_cast<int>(storey_mass.size());
  StructuralModel model;
  model.mass = Mat::Zero(n, n);
  model.stiffness = Mat::Zero(n, n);
  model.damping = Mat::Zero(n, n);
  model.influence = Vec::Ones(n);
  model.storey_stiffness = storey_stiffness;
  for (int i = 0; i < n; ++i) {
    if (!(storey_mass[i] > 0)) {
      throw std::invalid_argument("shear building: storey_mass[" + std::to_string(i) +
                                  "] must be > 0");
    }
    if (!(storey_stiffness[i] > 0)) {
      throw std::invalid_argument("shear building: storey_stiffness[" + std::to_string(i) +
                                  "] must be > 0");
    }
    model.mass(i, i) = storey_mass[i];
    const double k = storey_stiffness[i];
    model.stiffness(i, i) += k;
    if (i > 0) {
      model.stiffness(i - 1, i - 1) += k;
      model.stiffness(i - 1, i) -= k;
      model.stiffness(i, i - 1) -= k;
    }
  }
  return model;
}

StructuralModel make_sdof(double period, double zeta, double mass) {
  if (!(period > 0)) throw std::invalid_argument("SDOF: period must be > 0 s");
  if (!(mass > 0)) throw std::invalid_argument("SDOF: mass must be > 0 kg");
  if (zeta < 0) throw std::invalid_argument("SDOF: damping ratio must be >= 0");
  const double omega = 2.0 * std::numbers::pi / period;
  StructuralModel model = make_shear_building({mass}, {mass * omega * omega});
  model.damping(0, 0) = 2.0 * zeta * mass * omega;
  return model;
}

namespace {

// The highest mode's plain Lanczos: at most this many steps (a 10,000-DOF chain's top eigenvalues
// are 1e-8 apart; its Ritz value then settles to ~1e-7 in about 2000 steps, each O(nnz)), stopped
// when the Ritz value moves by less than this relative amount over 50 steps.
constexpr Eigen::Index kLanczosSteps = 4000;
constexpr double kLanczosTolerance = 1e-10;

// Eigenvalues of the symmetric tridiagonal (alpha, beta) below x: the negative pivots of
// T - x I = L D L^T (Sylvester's law of inertia), O(k).
Eigen::Index count_below(const std::vector<double>& alpha, const std::vector<double>& beta,
                         double x) {
  Eigen::Index count = 0;
  double pivot = 1.0;
  for (std::size_t i = 0; i < alpha.size(); ++i) {
    pivot = alpha[i] - x - (i > 0 ? beta[i - 1] * beta[i - 1] / pivot : 0.0);
    if (pivot == 0.0) pivot = -1e-300;  // x an eigenvalue: counted below, as bisection needs
    if (pivot < 0.0) ++count;
  }
  return count;
}

// Largest eigenvalue of a Lanczos run's tridiagonal by bisection between its Gershgorin bounds
// to 1e-14 relative: O(k) a step, where a dense tridiagonal solver is O(k^2).
double largest_of_tridiagonal(const std::vector<double>& alpha, const std::vector<double>& beta) {
  const auto k = static_cast<Eigen::Index>(alpha.size());
  double low = alpha[0], high = alpha[0];
  for (Eigen::Index i = 0; i < k; ++i) {
    const auto u = static_cast<std::size_t>(i);
    const double radius =
        (i > 0 ? std::abs(beta[u - 1]) : 0.0) + (i + 1 < k ? std::abs(beta[u]) : 0.0);
    low = std::min(low, alpha[u] - radius);
    high = std::max(high, alpha[u] + radius);
  }
  while (high - low > 1e-14 * std::max(std::abs(high), std::abs(low))) {
    const double middle = 0.5 * (low + high);
    if (middle <= low || middle >= high) break;
    (count_below(alpha, beta, middle) == k ? high : low) = middle;
  }
  return high;
}

// sqrt of the largest Ritz value of a plain Lanczos run (see max_omega in the header).
double lanczos_max_omega(const SparseMat& mass, const SparseMat& stiffness) {
  const Eigen::Index n = mass.rows();
  const Eigen::SimplicialLDLT<SparseMat> mass_factor(mass);
  if (mass_factor.info() != Eigen::Success || !(mass_factor.vectorD().array() > 0.0).all())
    throw std::invalid_argument("highest mode: M must be positive definite");
  // Lanczos in the M inner product on M^-1 K from a fixed start (reproducible), without
  // reorthogonalisation: the extreme Ritz value is unharmed by the lost orthogonality.
  Vec q = Vec::LinSpaced(n, 1.0, 2.0).array().sin() + 1.5, previous = Vec::Zero(n), w(n);
  q /= std::sqrt(q.dot(mass * q));
  std::vector<double> alpha, beta;
  double theta = 0.0;
  const Eigen::Index steps = std::min<Eigen::Index>(n, kLanczosSteps);
  for (Eigen::Index k = 0; k < steps; ++k) {
    const Vec kq = stiffness * q;
    alpha.push_back(q.dot(kq));
    w = mass_factor.solve(kq) - alpha.back() * q - (beta.empty() ? 0.0 : beta.back()) * previous;
    const double b = std::sqrt(std::max(w.dot(mass * w), 0.0));
    const bool last = k + 1 == steps || !(b > 1e-14 * std::abs(alpha.back()));
    if (last || (k + 1) % 50 == 0) {
      const double next = largest_of_tridiagonal(alpha, beta);
      const bool settled = std::abs(next - theta) <= kLanczosTolerance * std::abs(next);
      theta = next;
      if (last || settled) break;
    }
    beta.push_back(b);
    previous = q;
    q = w / b;
  }
  return std::sqrt(std::max(theta, 0.0));
}

}  // namespace

Modes modal_analysis(const Mat& mass, const Mat& stiffness) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Mat> solver(stiffness, mass);
  if (solver.info() != Eigen::Success) {
    throw std::invalid_argument("modal analysis failed: M must be positive definite");
  }
  Modes modes;
  modes.omega = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  modes.shapes = solver.eigenvectors();  // normalised so that Phi^T M Phi = I
  return modes;
}

Mat rayleigh_damping(const Mat& mass, const Mat& stiffness, double zeta, int mode_i, int mode_j) {
  const Modes modes = modal_analysis(mass, stiffness);
  const int n = static_cast<int>(modes.omega.size());
  if (n == 1) return 2.0 * zeta * modes.omega(0) * mass;
  if (mode_i < 1 || mode_j < 1 || mode_i > n || mode_j > n || mode_i == mode_j) {
    throw std::invalid_argument("Rayleigh damping: modes " + std::to_string(mode_i) + " and " +
                                std::to_string(mode_j) + " must be distinct and in 1.." +
                                std::to_string(n));
  }
  const double wi = modes.omega(mode_i - 1), wj = modes.omega(mode_j - 1);
  // zeta = a0 / (2 w) + a1 w / 2 at both frequencies.
  const double a0 = 2.0 * zeta * wi * wj / (wi + wj);
  const double a1 = 2.0 * zeta / (wi + wj);
  return a0 * mass + a1 * stiffness;
}

Mat modal_damping(const Mat& mass, const Mat& stiffness, double zeta) {
  const Modes modes = modal_analysis(mass, stiffness);
  const Vec diag = 2.0 * zeta * modes.omega;
  return mass * modes.shapes * diag.asDiagonal() * modes.shapes.transpose() * mass;
}

double max_omega(const StructuralModel& model) {
  if (model.known_max_omega > 0.0) return model.known_max_omega;
  if (model.is_sparse()) return lanczos_max_omega(model.sparse_mass, model.sparse_stiffness);
  return modal_analysis(model.mass, model.stiffness).omega.maxCoeff();
}

void remember_max_omega(StructuralModel& model) {
  model.known_max_omega = 0.0;
  model.known_max_omega = max_omega(model);
}

}  // namespace rths::core
