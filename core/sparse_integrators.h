#pragma once
// The explicit integrators of core/integrators.h on a model held sparse (StructuralModel::
// is_sparse(), core/sparse_structure.h): the same recurrences (core/explicit_schemes.h), with every matrix that the dense
// schemes invert factorised once (Eigen SimplicialLDLT, fill-reducing AMD ordering) and every
// product taken in O(nnz). A step costs O(nnz(M) + nnz(C) + nnz(K) + nnz(L)) and allocates
// nothing (the LDL^T solves are done by hand: Eigen's own solve permutes in place through a
// temporary). Units SI: m, m/s, m/s^2, N, s.
//
//   EXPLICIT_NEWMARK, CENTRAL_DIFFERENCE  factor M + dt/2 C
//   CHEN_RICLES   factor D = 4M + 2dt C + dt^2 K0 and M: A a = 4 D^-1 (M a)
//   ALPHA_OS      factor M + alpha gamma dt C + alpha beta dt^2 K0
//   KR_ALPHA      D = M + S, S = gamma dt C + beta dt^2 K0, B = (1 - alpha_m) M + (1 - alpha_f) S,
//                 E = alpha_m M + alpha_f S (= D - B): A1 a = D^-1 (M a), M A3 a = M D^-1 (B a),
//                 and M^ = M (I - A3) = M D^-1 E, so M^ a+ = f solves as E a+ = D (M^-1 f):
//                 factor D, E and M; no dense A1, A3 or M^.
// Results equal the dense schemes' to rounding (~1e-12 relative), not bit for bit: the sums run
// in another order.
//
// Schemes that need dense matrices stay dense (make_integrator takes their dense path):
// NEWMARK_AVERAGE_ACCELERATION (a dense tangent, factorised every iteration) and EXACT_ZOH (the
// matrix exponential of the 2n x 2n state matrix, dense by nature). They refuse models held
// sparse only and models above kDenseSchemeMaxDofs, naming the limit.

#include <memory>

#include "core/integrator.h"

namespace rths::core {

constexpr int kDenseSchemeMaxDofs = 2000;

// The sparse form of `kind` for a model held sparse; null for a scheme that stays dense.
// Throws std::invalid_argument as make_integrator does (alpha_os, rho_infinity out of range),
// or when a matrix to factorise is not positive definite.
std::unique_ptr<Integrator> make_sparse_integrator(IntegratorKind kind,
                                                   const StructuralModel& model, double dt,
                                                   const IntegratorParameters& parameters);

// Throws std::invalid_argument naming `kind`, the model's DOFs and kDenseSchemeMaxDofs when a
// scheme that needs dense matrices cannot take `model` (held sparse only, or too large).
void require_dense_scheme_fits(IntegratorKind kind, const StructuralModel& model);

}  // namespace rths::core
