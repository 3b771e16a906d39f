#include "core/loop_critical_delay.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/sparse_structure.h"

namespace rths::core {

namespace {

// value b b' as a sparse matrix (n x n) from b's nonzeros: no n x n dense copy of a large model.
SparseMat sparse_outer(const Vec& b, double value) {
  std::vector<Eigen::Index> nonzero;
  for (Eigen::Index i = 0; i < b.size(); ++i)
    if (b[i] != 0.0) nonzero.push_back(i);
  std::vector<Eigen::Triplet<double>> entries;
  for (const Eigen::Index i : nonzero)
    for (const Eigen::Index j : nonzero) entries.emplace_back(i, j, value * b[i] * b[j]);
  SparseMat out(b.size(), b.size());
  out.setFromTriplets(entries.begin(), entries.end());
  return out;
}

// The whole structure: the parts' dashpots and masses added back to C_N and M_N (both
// representations the model holds).
StructuralModel whole_structure(const StructuralModel& model,
                                const std::vector<DelayedPart>& parts) {
  StructuralModel whole = model;
  whole.known_max_omega = 0.0;  // M and C change
  for (const DelayedPart& p : parts) {
    if (whole.damping.size() > 0) whole.damping += p.damping * p.row * p.row.transpose();
    if (whole.mass.size() > 0) whole.mass += p.mass * p.row * p.row.transpose();
    if (!whole.is_sparse()) continue;
    whole.sparse_damping += sparse_outer(p.row, p.damping);
    whole.sparse_mass += sparse_outer(p.row, p.mass);
  }
  return whole;
}

}  // namespace

CriticalDelayCheck check_loop_critical_delay(const StructuralModel& model,
                                             std::vector<DelayedPart> parts, IntegratorKind kind,
                                             double dt, double lag) {
  const int n = model.dofs();
  SparseMat k_experimental(n, n);  // sum k_j b_j b_j', O(nnz of the rows): no n x n matrix
  bool dynamic = false;
  for (std::size_t j = 0; j < parts.size(); ++j) {
    if (parts[j].row.size() != n)
      throw std::invalid_argument("critical delay check: part " + std::to_string(j + 1) +
                                  "'s row b must hold " + std::to_string(n) + " entries");
    k_experimental += sparse_outer(parts[j].row, parts[j].stiffness);
    dynamic = dynamic || parts[j].damping != 0.0 || parts[j].mass != 0.0;
    parts[j].predicted = false;
    parts[j].lag = 0.0;
  }
  if (!dynamic) return check_modal_critical_delay(model, k_experimental, kind, dt, lag);
  CriticalDelayCheck check =
      check_modal_critical_delay(whole_structure(model, parts), k_experimental, kind, dt, lag);
  constexpr int kSparseModes = 20;  // as core::check_modal_critical_delay
  const Modes modes = lowest_modes(model, model.is_sparse() ? std::min(kSparseModes, n - 1) : n);
  const CoupledLoopStability loop = coupled_loop_stability(model, parts, modes);
  if (!check.coupled) check.modal_continuous = check.continuous;
  check.coupled = true;
  check.continuous = loop.common_critical_lag;
  check.assumed = loop.assumed +
                  " for the continuous limit, every link at the same lag; the discrete limit by "
                  "the modal approximation of the whole structure (each mode an SDOF with its "
                  "modal damping, the specimens' dashpots taken undelayed there)";
  if (loop.common_critical_lag)
    check.govern_by_mode_nearest(loop.common_omega, modes, k_experimental);
  return check;
}

}  // namespace rths::core
