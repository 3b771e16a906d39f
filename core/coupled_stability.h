#pragma once
// Critical delay of a structure whose experimental parts all lag by one delay tau, with the
// coupling between modes that the delayed force adds (core/stability.h's modal check ignores it).
//
//   M u'' + C u' + K_N u + K_e u(t - tau) = 0,   K_N = K - K_e,  K_e = sum_e k_e b_e b_e^T
//
// Inputs: M, C, K (SI) of the whole structure and K_e (N/m, n x n, symmetric positive
// semi-definite: the experimental parts at their initial stiffness). Output: the smallest tau (s)
// at which a characteristic root crosses the imaginary axis, the frequency of that crossing, and
// what was assumed.
//
// In the q lowest mass-normalised modes Phi of (M, K) (q = n up to kMaxModes; else the lowest
// kMaxModes, a truncation the `assumed` text states), A(w) = Phi' (K_N - M w^2 + i w C) Phi.
// A root crosses at s = i w when det(A(w) + z K~_e) = 0 with z = e^{-i w tau} on the unit circle.
// With K~_e = Phi' K_e Phi = U S U' (rank m, one per independent experimental part),
// det(A + z K~_e) = det(A) det(I + z G(w)), G = S^1/2 U' A^-1 U S^1/2 (m x m), so a crossing is
// a w where an eigenvalue lambda of G has |lambda| = 1; then z = -1 / lambda and
// tau = ((-arg z) mod 2 pi) / w (the first branch; later ones add 2 pi / w). Crossings are found
// where the count of |lambda| > 1 changes on a log grid of kGridPoints w from 1e-3 omega_1 to
// 10 omega_q, each refined by 60 bisections. Stability at tau = 0 is assumed (K_N + K_e = K
// positive definite, C >= 0). For one DOF, or a K_e and C that the modes diagonalise, this is the
// modal check's SDOF result.

#include <optional>
#include <string>

#include "core/structure.h"

namespace rths::core {

struct CoupledStability {
  static constexpr int kMaxModes = 24;
  static constexpr int kGridPoints = 3000;
  std::optional<double> critical_delay;  // s; empty: no crossing (stable for every delay)
  double omega = 0.0;                    // rad/s at the governing crossing
  int modes_kept = 0;                    // q
  int parts = 0;                         // m, the rank of K_e
  std::string assumed;
};

// `modes`: mass-normalised modes of (M, K), ascending (all n, or the lowest ones a sparse solver
// found). @pre model.mass, damping, stiffness and k_experimental n x n; modes n x (at least 1).
CoupledStability coupled_critical_delay(const StructuralModel& model, const Mat& k_experimental,
                                        const Modes& modes);

// Whether the q lowest modes diagonalise K_e and C (to 1e-9 of their diagonals): then the modal
// check is exact and the coupled analysis adds nothing.
bool modes_decouple(const StructuralModel& model, const Mat& k_experimental, const Modes& modes);

}  // namespace rths::core
