#pragma once
// Large, sparse structural models: when a model is held sparse, its lowest modes from a sparse
// eigensolver (Spectra, Lanczos on Eigen sparse matrices; its highest: core::max_omega) and the
// definiteness checks of its matrices, all without an n x n dense problem. Units SI (kg, N s/m,
// N/m, rad/s).
//
// The fill rule (hold_sparse_if_sparse): a model is held sparse when n >= kSparseMinDofs and the
// nonzeros of M + C + K fill at most kSparseMaxFill of n^2. Why:
//   - a dense step costs ~ 3 n^2 multiply-adds (an inverse and C times a vector, streamed
//     contiguously, 4 per cycle with SIMD); a sparse one ~ 2 nnz(L) + nnz(C) + nnz(M), each an
//     indexed load (~1 per cycle): sparse wins when nnz is below ~ n^2 / 10; a condensed model
//     (full K) stays dense;
//   - below 100 DOFs a dense step is a few microseconds and dense results stay bit-identical to
//     what the tests and the README's tables were made with.
//
//   lowest_modes(model, count): the `count` lowest (omega, mass-normalised phi) pairs, ascending;
//     dense models: the full dense analysis (core::modal_analysis, every mode, as before); sparse:
//     shift-invert Lanczos of K phi = lambda M phi about a shift just below 0 (so a free-floating
//     K, semi-definite, factorises).
//   check_sparse_definite: symmetric positive (semi-)definite by Sylvester's law of inertia: the
//     LDL^T of A - s I (strictly) or A + s I (semi) with s = 1e-9 ||A||_inf has only positive
//     pivots. ||A||_inf >= the largest |eigenvalue|, so the tolerance is that of the dense check
//     (1e-9 of the largest eigenvalue) or looser by at most that ratio.

#include <optional>
#include <string>

#include "core/structure.h"

namespace rths::core {

constexpr int kSparseMinDofs = 100;
constexpr double kSparseMaxFill = 0.05;  // nnz(M + C + K) / n^2

// Whether a model of n DOFs with `nonzeros` nonzero entries in M + C + K is held sparse.
bool prefer_sparse(Eigen::Index n, Eigen::Index nonzeros);
// Fills model.sparse_* from the dense M, C, K when prefer_sparse; clears them otherwise (a full
// C from modal damping makes the model dense again). A model held sparse only (no dense copies)
// stays as it is. Throws std::logic_error when it would clear a model whose low_rank_damping
// needs it held sparse.
void hold_sparse_if_sparse(StructuralModel& model);
// A model held sparse only (no dense copies): for models too large to hold densely.
StructuralModel make_sparse_model(SparseMat mass, SparseMat damping, SparseMat stiffness,
                                  Vec influence);

// M x (kg m, ...) for either representation.
Vec mass_times(const StructuralModel& model, const Vec& x);
// phi^T C phi for either representation (the low-rank term included).
double damping_quadratic(const StructuralModel& model, const Vec& phi);
// Phi^T C Phi (q x q, N s/m per unit modal mass) of the columns of `shapes`, for either
// representation (the low-rank term included): what a modal analysis of C must use, since a
// model whose modal damping is kept as factors holds only C's sparse part in `damping`.
Mat damping_in_modes(const StructuralModel& model, const Mat& shapes);

Modes lowest_modes(const StructuralModel& model, int count);
Modes sparse_lowest_modes(const SparseMat& mass, const SparseMat& stiffness, int count);

// Empty when A passes; else the problem ("is not positive definite: ...").
std::optional<std::string> check_sparse_definite(const SparseMat& a, bool strictly);

// Modal damping of a model held sparse through its lowest modes, kept as factors (never n x n):
//   m, the modes kept: the fewest of the lowest whose effective masses along iota,
//     (phi_i^T M iota)^2, reach kModalMassShare of iota^T M iota (the 90 % ASCE 7 12.9.1.1 asks of
//     a modal analysis), at least kModalMinModes, at most kModalMaxModes and n - 2;
//   modes 1..m get zeta exactly; modes j > m get stiffness-proportional damping a1 K with
//     a1 = 2 zeta / omega_{m+1}: zeta_j = zeta omega_j / omega_{m+1} >= zeta (zeta at mode m + 1,
//     more the higher, as Rayleigh's upper branch; OpenSees's modalDamping leaves them undamped,
//     which a lagging specimen's negative damping can drive);
//   C = a1 K + sum_{i<=m} (2 zeta omega_i - a1 omega_i^2) (M phi_i)(M phi_i)^T: a1 K in
//     sparse_damping (and damping, where held dense), the sum in low_rank_damping (coefficients
//     > 0 since omega_i < omega_{m+1}).
// Cost: a shift-invert Lanczos for m + 1 modes (twice or more only when 20 modes hold < 90 %),
// O(n m) memory. Throws std::invalid_argument (the field, the reason, the fix) when the model is
// not held sparse, zeta is outside (0, 1] or the eigensolver fails.
constexpr int kModalMinModes = 20;
constexpr int kModalMaxModes = 200;
constexpr double kModalMassShare = 0.9;
struct SparseModalDamping {
  int modes = 0;                              // m
  double mass_share = 0.0;                    // of iota^T M iota held by modes 1..m
  double omega_kept = 0.0, omega_next = 0.0;  // rad/s, omega_m and omega_{m+1}
  double stiffness_factor = 0.0;              // a1, s
  std::string text;                           // the choice in one line, for the study's notes
};
SparseModalDamping sparse_modal_damping(StructuralModel& model, double zeta);

// Rayleigh damping of a sparse model (C = a0 M + a1 K from modes i and j, 1-based), set in both
// representations when the model also holds dense ones.
void sparse_rayleigh_damping(StructuralModel& model, double zeta, int mode_i, int mode_j);

}  // namespace rths::core
