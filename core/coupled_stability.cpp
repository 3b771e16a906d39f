#include "core/coupled_stability.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "core/simulation.h"
#include "core/sparse_structure.h"

namespace rths::core {
namespace {

using Complex = std::complex<double>;
using CMat = Eigen::MatrixXcd;

// One part in the kept modes: w = Phi' b (q), its undelayed gain p(i w) and delayed gain h(i w)
// (header), its own lag.
struct ModalPart {
  Vec shape;
  double now_stiffness = 0.0, now_damping = 0.0;                     // k^, c^
  double late_stiffness = 0.0, late_damping = 0.0, late_mass = 0.0;  // k - k^, c - c^, m
  double lag = 0.0;                                                  // s
  Complex now(double w) const { return {now_stiffness, w * now_damping}; }
  Complex late(double w) const { return {late_stiffness - w * w * late_mass, w * late_damping}; }
};

// The loop in the kept modes: Omega^2 - K~_e, the modes' damping, the parts.
struct ModalLoop {
  Vec omega_squared;  // q
  Mat numerical;      // q x q
  Mat damping;        // q x q
  std::vector<ModalPart> parts;
};

// Which parts share the varying lag; every other part sits at lags[j] (s; 0: undelayed).
struct Scan {
  std::vector<int> varying;
  std::vector<double> lags;
};

struct Crossing {
  double lag = 0.0;    // s, first branch
  double omega = 0.0;  // rad/s
};

int kept_count(const Modes& modes) {
  return std::min(static_cast<int>(modes.omega.size()), CoupledStability::kMaxModes);
}

ModalLoop modal_base(const StructuralModel& model, const Modes& modes, int q) {
  ModalLoop loop;
  const Mat phi = modes.shapes.leftCols(q);
  loop.omega_squared = modes.omega.head(q).array().square();
  loop.damping = damping_in_modes(model, phi);
  loop.numerical = Mat(loop.omega_squared.asDiagonal());
  return loop;
}

// Eigenvalues of G(w) = H_S W_S' A(w)^-1 W_S for the scan's varying parts S.
Eigen::VectorXcd loop_eigenvalues(const ModalLoop& loop, const Scan& scan, double w) {
  CMat a = loop.numerical.cast<Complex>();
  a.diagonal().array() -= w * w;
  a += Complex(0.0, w) * loop.damping.cast<Complex>();
  std::vector<bool> varies(loop.parts.size(), false);
  for (int j : scan.varying) varies[static_cast<std::size_t>(j)] = true;
  for (std::size_t j = 0; j < loop.parts.size(); ++j) {
    const ModalPart& part = loop.parts[j];
    Complex gain = part.now(w);
    if (!varies[j]) gain += part.late(w) * std::exp(Complex(0.0, -w * scan.lags[j]));
    if (gain != Complex(0.0, 0.0))
      a += gain * (part.shape * part.shape.transpose()).cast<Complex>();
  }
  const auto s = static_cast<Eigen::Index>(scan.varying.size());
  CMat w_factor(a.rows(), s);
  Eigen::VectorXcd h(s);
  for (Eigen::Index c = 0; c < s; ++c) {
    const ModalPart& part = loop.parts[static_cast<std::size_t>(scan.varying[c])];
    w_factor.col(c) = part.shape.cast<Complex>();
    h[c] = part.late(w);
  }
  const CMat g = h.asDiagonal() * (w_factor.transpose() * a.partialPivLu().solve(w_factor));
  return Eigen::ComplexEigenSolver<CMat>(g, false).eigenvalues();
}

int outside_unit_circle(const Eigen::VectorXcd& lambda) {
  int count = 0;
  for (const Complex& l : lambda) count += std::abs(l) > 1.0 ? 1 : 0;
  return count;
}

// The first-branch delay (s) of the eigenvalue nearest the unit circle at w.
double crossing_delay(const Eigen::VectorXcd& lambda, double w) {
  const auto distance = [](const Complex& l) {
    return std::abs(l) > 0.0 ? std::abs(std::log(std::abs(l))) : HUGE_VAL;
  };
  Eigen::Index nearest = 0;
  for (Eigen::Index j = 1; j < lambda.size(); ++j)
    if (distance(lambda[j]) < distance(lambda[nearest])) nearest = j;
  const Complex z = -1.0 / lambda[nearest];
  double theta = -std::arg(z);
  if (theta < 0) theta += 2.0 * std::numbers::pi;
  return theta / w;
}

// The smallest first-branch lag over the crossings of the scan (header: grid and bisection).
std::optional<Crossing> first_crossing(const ModalLoop& loop, const Scan& scan) {
  const auto q = static_cast<int>(loop.omega_squared.size());
  const double lo = std::log(1e-3 * std::sqrt(loop.omega_squared[0]));
  const double hi = std::log(10.0 * std::sqrt(loop.omega_squared[q - 1]));
  const auto count_at = [&](double w) {
    return outside_unit_circle(loop_eigenvalues(loop, scan, w));
  };
  std::optional<Crossing> out;
  double previous_w = std::exp(lo);
  int previous = count_at(previous_w);
  for (int i = 1; i < CoupledStability::kGridPoints; ++i) {
    const double w = std::exp(lo + (hi - lo) * i / (CoupledStability::kGridPoints - 1));
    const int count = count_at(w);
    if (count != previous) {
      double a = previous_w, b = w;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (a + b);
        (count_at(mid) == previous ? a : b) = mid;
      }
      const double crossing = 0.5 * (a + b);
      const double tau = crossing_delay(loop_eigenvalues(loop, scan, crossing), crossing);
      if (!out || tau < out->lag) out = Crossing{tau, crossing};
    }
    previous = count;
    previous_w = w;
  }
  return out;
}

std::string modes_text(int q, int n) {
  return q == n ? "all " + std::to_string(n) + " modes of (M, K)"
                : "the lowest " + std::to_string(q) + " of " + std::to_string(n) +
                      " modes of (M, K) (higher modes left out)";
}

std::string assumed_text(int q, int n, int parts) {
  return "coupled analysis of the delayed loop (" + std::to_string(parts) + " experimental part" +
         (parts == 1 ? "" : "s") + ", every one at the same lag and its initial stiffness) in " +
         modes_text(q, n);
}

void require_part(const DelayedPart& part, int n, std::size_t index) {
  const std::string where = "coupled loop: part " + std::to_string(index + 1) + ": ";
  if (part.row.size() != n || !part.row.allFinite() || part.row.isZero(0.0))
    throw std::invalid_argument(where + "its row b must hold " + std::to_string(n) +
                                " finite entries, not all 0");
  if (!(std::isfinite(part.stiffness) && part.stiffness > 0))
    throw std::invalid_argument(where + "its stiffness must be > 0 N/m");
  for (const double value : {part.damping, part.mass, part.model_stiffness, part.model_damping})
    if (!std::isfinite(value))
      throw std::invalid_argument(where + "its damping, mass and model must be finite");
  if (!(std::isfinite(part.lag) && part.lag >= 0))
    throw std::invalid_argument(where + "its lag must be >= 0 s");
}

ModalLoop modal_loop(const StructuralModel& model, const std::vector<DelayedPart>& parts,
                     const Modes& modes, int q) {
  ModalLoop loop = modal_base(model, modes, q);
  const Mat phi = modes.shapes.leftCols(q);
  for (std::size_t j = 0; j < parts.size(); ++j) {
    const DelayedPart& p = parts[j];
    require_part(p, model.dofs(), j);
    ModalPart m;
    m.shape = phi.transpose() * p.row;
    m.now_stiffness = p.predicted ? p.model_stiffness : 0.0;
    m.now_damping = p.predicted ? p.model_damping : 0.0;
    m.late_stiffness = p.stiffness - m.now_stiffness;
    m.late_damping = p.damping - m.now_damping;
    m.late_mass = p.mass;
    m.lag = p.lag;
    loop.numerical -= p.stiffness * m.shape * m.shape.transpose();
    loop.parts.push_back(std::move(m));
  }
  return loop;
}

// Raises each part in `order` from lag 0 to its own in turn, the earlier ones at theirs and the
// rest at `lags` (0 on entry). Returns the part whose first crossing came before its own lag
// (and that lag, s), or nothing: no root crossed on the way. `lags` ends at the lags reached.
std::optional<std::pair<int, double>> staircase(const ModalLoop& loop,
                                                const std::vector<int>& order,
                                                std::vector<double>& lags) {
  for (int j : order) {
    const std::optional<Crossing> c = first_crossing(loop, {{j}, lags});
    const double own = loop.parts[static_cast<std::size_t>(j)].lag;
    if (c && c->lag <= own) return std::make_pair(j, c->lag);
    lags[static_cast<std::size_t>(j)] = own;
  }
  return std::nullopt;
}

PartLimit part_limit(const ModalLoop& loop, int l) {
  const auto m = static_cast<int>(loop.parts.size());
  std::vector<int> others;
  for (int j = 0; j < m; ++j)
    if (j != l) others.push_back(j);
  std::vector<double> lags(loop.parts.size(), 0.0);
  PartLimit out;
  if (const auto crossed = staircase(loop, others, lags)) {
    out.crossed_before = crossed->first;
    out.crossed_at = crossed->second;
    return out;
  }
  if (const std::optional<Crossing> c = first_crossing(loop, {{l}, lags})) {
    out.critical_lag = c->lag;
    out.omega = c->omega;
  }
  return out;
}

}  // namespace

CoupledStability coupled_critical_delay(const StructuralModel& model, const Mat& k_experimental,
                                        const Modes& modes) {
  return coupled_critical_delay(model, SparseMat(k_experimental.sparseView()), modes);
}

CoupledStability coupled_critical_delay(const StructuralModel& model,
                                        const SparseMat& k_experimental, const Modes& modes) {
  const int q = kept_count(modes);
  ModalLoop loop = modal_base(model, modes, q);
  const Mat phi = modes.shapes.leftCols(q);
  const Mat k_e = phi.transpose() * (k_experimental * phi);
  loop.numerical -= k_e;
  // K~_e's independent directions, each a part of stiffness its eigenvalue.
  const Eigen::SelfAdjointEigenSolver<Mat> directions(0.5 * (k_e + k_e.transpose()));
  const double largest = directions.eigenvalues().cwiseAbs().maxCoeff();
  Scan scan;
  for (int j = 0; j < q; ++j) {
    if (!(directions.eigenvalues()[j] > 1e-12 * largest)) continue;
    ModalPart part;
    part.shape = directions.eigenvectors().col(j);
    part.late_stiffness = directions.eigenvalues()[j];
    scan.varying.push_back(static_cast<int>(loop.parts.size()));
    loop.parts.push_back(std::move(part));
  }
  scan.lags.assign(loop.parts.size(), 0.0);
  CoupledStability out;
  out.modes_kept = q;
  out.parts = static_cast<int>(loop.parts.size());
  out.assumed = assumed_text(q, model.dofs(), out.parts);
  if (out.parts == 0) return out;
  if (const std::optional<Crossing> c = first_crossing(loop, scan)) {
    out.critical_delay = c->lag;
    out.omega = c->omega;
  }
  return out;
}

bool modes_decouple(const StructuralModel& model, const Mat& k_experimental, const Modes& modes) {
  return modes_decouple(model, SparseMat(k_experimental.sparseView()), modes);
}

bool modes_decouple(const StructuralModel& model, const SparseMat& k_experimental,
                    const Modes& modes) {
  const Mat phi = modes.shapes.leftCols(kept_count(modes));
  for (const Mat& x :
       {Mat(phi.transpose() * (k_experimental * phi)), damping_in_modes(model, phi)}) {
    const double scale = x.diagonal().cwiseAbs().maxCoeff();
    Mat off = x;
    off.diagonal().setZero();
    if (off.cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  }
  return true;
}

CoupledLoopStability coupled_loop_stability(const StructuralModel& model,
                                            const std::vector<DelayedPart>& parts,
                                            const Modes& modes) {
  const int q = kept_count(modes);
  const ModalLoop loop = modal_loop(model, parts, modes, q);
  const auto m = static_cast<int>(parts.size());
  CoupledLoopStability out;
  out.modes_kept = q;
  out.assumed = "coupled analysis of the delayed loop (" + std::to_string(m) + " link" +
                (m == 1 ? "" : "s") +
                ", each specimen at its initial stiffness with its dashpot and mass, a predicted "
                "link's model frozen as it is given, continuous time) in " +
                modes_text(q, model.dofs());
  out.stable = true;
  if (m == 0) return out;
  std::vector<int> every(static_cast<std::size_t>(m));
  for (int j = 0; j < m; ++j) every[static_cast<std::size_t>(j)] = j;
  if (const auto c = first_crossing(loop, {every, std::vector<double>(parts.size(), 0.0)})) {
    out.common_critical_lag = c->lag;
    out.common_omega = c->omega;
  }
  for (int l = 0; l < m; ++l) out.parts.push_back(part_limit(loop, l));
  const PartLimit& first = out.parts.front();
  if (first.crossed_before >= 0) {
    out.stable = false;
    out.crossed = first.crossed_before;
    out.crossed_at = first.crossed_at;
  } else if (first.critical_lag && *first.critical_lag <= parts.front().lag) {
    out.stable = false;
    out.crossed = 0;
    out.crossed_at = *first.critical_lag;
  }
  return out;
}

std::vector<DelayedPart> setup_loop_parts(const HybridSetup& setup,
                                          const std::vector<double>& lags) {
  const HybridPartition& partition = setup.partition;
  const std::size_t actuators = partition.actuator_storeys.size();
  if (lags.size() != actuators)
    throw std::invalid_argument("coupled loop: " + std::to_string(lags.size()) + " lags for " +
                                std::to_string(actuators) + " actuators");
  const int n = setup.model.dofs();
  // Row s of B (drifts = B u) is B' e_s, the DOF forces of a unit shear at channel s: O(n) an
  // actuator, no storeys x n matrix.
  const StoreyAssembly assembly = partition.assembly();
  Vec row(n);
  std::vector<DelayedPart> parts;
  for (std::size_t a = 0; a < actuators; ++a) {
    const int s = partition.actuator_storeys[a];
    const RestoringForceModel* specimen = partition.experimental[static_cast<std::size_t>(s)].get();
    if (!specimen)
      throw std::invalid_argument("coupled loop: actuator " + std::to_string(a + 1) +
                                  " has no specimen");
    DelayedPart part;
    assembly.dof_forces(Vec::Unit(assembly.storeys(), s), row);
    part.row = row;
    part.stiffness = specimen->initial_stiffness();
    if (const auto* inertial = dynamic_cast<const InertialSpecimen*>(specimen)) {
      part.damping = inertial->damping();
      part.mass = inertial->mass();
    }
    if (a < setup.predictors.size() && setup.predictors[a]) {
      const ForcePredictor model(*setup.predictors[a], setup.dt, "force predictor", specimen);
      part.predicted = true;
      // Its initial tangent: the parameters' stiffness, whatever terms share it.
      part.model_stiffness = setup.predictors[a]->stiffness;
      part.model_damping = model.damping();
    }
    part.lag = lags[a];
    parts.push_back(std::move(part));
  }
  return parts;
}

CoupledLoopStability setup_loop_stability(const HybridSetup& setup, const std::vector<double>& lags,
                                          PredictorModels models) {
  constexpr int kSparseModes = 20;  // as core::check_modal_critical_delay
  const int n = setup.model.dofs();
  const Modes modes =
      lowest_modes(setup.model, setup.model.is_sparse() ? std::min(kSparseModes, n - 1) : n);
  std::vector<DelayedPart> parts = setup_loop_parts(setup, lags);
  if (models == PredictorModels::kFittedToTheDeclaredSpecimen)
    for (DelayedPart& part : parts)
      if (part.predicted) {
        part.model_stiffness = part.stiffness;
        part.model_damping = part.damping;
      }
  return coupled_loop_stability(setup.model, parts, modes);
}

}  // namespace rths::core
