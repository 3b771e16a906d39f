#include "core/coupled_stability.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace rths::core {
namespace {

using Complex = std::complex<double>;
using CMat = Eigen::MatrixXcd;

// The problem in the kept modes: stiffness Omega^2 - K~_e, damping C~, and K~_e's factor
// W = U S^1/2 (q x m), so that K~_e = W W'.
struct ModalProblem {
  Vec omega_squared;  // q
  Mat damping;        // q x q
  Mat numerical;      // q x q: Omega^2 - K~_e
  Mat factor;         // q x m
};

struct KeptModes {
  const Modes& modes;
  int q = 0;
};

KeptModes kept_modes(const Modes& modes) {
  return {modes, std::min(static_cast<int>(modes.omega.size()), CoupledStability::kMaxModes)};
}

ModalProblem modal_problem(const StructuralModel& model, const Mat& k_experimental,
                           const KeptModes& kept) {
  const Mat phi = kept.modes.shapes.leftCols(kept.q);
  ModalProblem p;
  p.omega_squared = kept.modes.omega.head(kept.q).array().square();
  p.damping = phi.transpose() * model.damping * phi;
  const Mat k_e = phi.transpose() * k_experimental * phi;
  p.numerical = Mat(p.omega_squared.asDiagonal()) - k_e;
  const Eigen::SelfAdjointEigenSolver<Mat> parts(0.5 * (k_e + k_e.transpose()));
  const double largest = parts.eigenvalues().cwiseAbs().maxCoeff();
  std::vector<int> kept_parts;
  for (int j = 0; j < kept.q; ++j)
    if (parts.eigenvalues()[j] > 1e-12 * largest) kept_parts.push_back(j);
  p.factor.resize(kept.q, static_cast<Eigen::Index>(kept_parts.size()));
  for (std::size_t c = 0; c < kept_parts.size(); ++c)
    p.factor.col(static_cast<Eigen::Index>(c)) =
        parts.eigenvectors().col(kept_parts[c]) * std::sqrt(parts.eigenvalues()[kept_parts[c]]);
  return p;
}

// Eigenvalues of G(w) = W' A(w)^-1 W.
Eigen::VectorXcd loop_eigenvalues(const ModalProblem& p, double w) {
  CMat a = p.numerical.cast<Complex>();
  a.diagonal().array() -= w * w;
  a += Complex(0.0, w) * p.damping.cast<Complex>();
  const CMat w_factor = p.factor.cast<Complex>();
  const CMat g = w_factor.transpose() * a.partialPivLu().solve(w_factor);
  return Eigen::ComplexEigenSolver<CMat>(g, false).eigenvalues();
}

int outside_unit_circle(const Eigen::VectorXcd& lambda) {
  int count = 0;
  for (const Complex& l : lambda) count += std::abs(l) > 1.0 ? 1 : 0;
  return count;
}

// The first-branch delay (s) of the eigenvalue nearest the unit circle at w.
double crossing_delay(const Eigen::VectorXcd& lambda, double w) {
  Eigen::Index nearest = 0;
  for (Eigen::Index j = 1; j < lambda.size(); ++j)
    if (std::abs(std::log(std::abs(lambda[j]))) < std::abs(std::log(std::abs(lambda[nearest]))))
      nearest = j;
  const Complex z = -1.0 / lambda[nearest];
  double theta = -std::arg(z);
  if (theta < 0) theta += 2.0 * std::numbers::pi;
  return theta / w;
}

std::string assumed_text(int q, int n, int parts) {
  std::string text = "coupled analysis of the delayed loop (" + std::to_string(parts) +
                     " experimental part" + (parts == 1 ? "" : "s") +
                     ", every one at the same lag and its initial stiffness) in ";
  text += q == n ? "all " + std::to_string(n) + " modes of (M, K)"
                 : "the lowest " + std::to_string(q) + " of " + std::to_string(n) +
                       " modes of (M, K) (higher modes left out)";
  return text;
}

}  // namespace

CoupledStability coupled_critical_delay(const StructuralModel& model, const Mat& k_experimental,
                                        const Modes& modes) {
  const KeptModes kept = kept_modes(modes);
  const ModalProblem p = modal_problem(model, k_experimental, kept);
  CoupledStability out;
  out.modes_kept = kept.q;
  out.parts = static_cast<int>(p.factor.cols());
  out.assumed = assumed_text(kept.q, model.dofs(), out.parts);
  if (out.parts == 0) return out;
  const double lo = std::log(1e-3 * std::sqrt(p.omega_squared[0]));
  const double hi = std::log(10.0 * std::sqrt(p.omega_squared[kept.q - 1]));
  double previous_w = std::exp(lo);
  int previous = outside_unit_circle(loop_eigenvalues(p, previous_w));
  for (int i = 1; i < CoupledStability::kGridPoints; ++i) {
    const double w = std::exp(lo + (hi - lo) * i / (CoupledStability::kGridPoints - 1));
    const int count = outside_unit_circle(loop_eigenvalues(p, w));
    if (count != previous) {
      double a = previous_w, b = w;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (a + b);
        (outside_unit_circle(loop_eigenvalues(p, mid)) == previous ? a : b) = mid;
      }
      const double crossing = 0.5 * (a + b);
      const double tau = crossing_delay(loop_eigenvalues(p, crossing), crossing);
      if (!out.critical_delay || tau < *out.critical_delay) {
        out.critical_delay = tau;
        out.omega = crossing;
      }
    }
    previous = count;
    previous_w = w;
  }
  return out;
}

bool modes_decouple(const StructuralModel& model, const Mat& k_experimental, const Modes& modes) {
  const KeptModes kept = kept_modes(modes);
  const Mat phi = kept.modes.shapes.leftCols(kept.q);
  for (const Mat& x :
       {Mat(phi.transpose() * k_experimental * phi), Mat(phi.transpose() * model.damping * phi)}) {
    const double scale = x.diagonal().cwiseAbs().maxCoeff();
    Mat off = x;
    off.diagonal().setZero();
    if (off.cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  }
  return true;
}

}  // namespace rths::core
