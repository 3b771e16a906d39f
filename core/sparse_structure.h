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
// C from modal damping makes the model dense again).
void hold_sparse_if_sparse(StructuralModel& model);
// A model held sparse only (no dense copies): for models too large to hold densely.
StructuralModel make_sparse_model(SparseMat mass, SparseMat damping, SparseMat stiffness,
                                  Vec influence);

// M x (kg m, ...) for either representation.
Vec mass_times(const StructuralModel& model, const Vec& x);
// phi^T C phi for either representation.
double damping_quadratic(const StructuralModel& model, const Vec& phi);

Modes lowest_modes(const StructuralModel& model, int count);
Modes sparse_lowest_modes(const SparseMat& mass, const SparseMat& stiffness, int count);

// Empty when A passes; else the problem ("is not positive definite: ...").
std::optional<std::string> check_sparse_definite(const SparseMat& a, bool strictly);

// Rayleigh damping of a sparse model (C = a0 M + a1 K from modes i and j, 1-based), set in both
// representations when the model also holds dense ones.
void sparse_rayleigh_damping(StructuralModel& model, double zeta, int mode_i, int mode_j);

}  // namespace rths::core
