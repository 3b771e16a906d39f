#include "core/structure.h"

#include "core/sparse_structure.h"

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
  if (model.is_sparse()) return sparse_max_omega(model.sparse_mass, model.sparse_stiffness);
  return modal_analysis(model.mass, model.stiffness).omega.maxCoeff();
}

}  // namespace rths::core
