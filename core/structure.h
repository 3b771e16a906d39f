#pragma once
// Structural models: lumped-mass shear buildings (an SDOF system is a one-storey building) with
// mass M, damping C and stiffness K as Eigen matrices, plus the ground-motion influence vector.
//
// Equation of motion (relative displacement u, m):  M a + C v + r(u) = -M iota a_g
// DOF i is floor i (1-based in docs, 0-based in code); storey i joins floor i-1 (ground for i=0)
// to floor i. Storey drift d_i = u_i - u_{i-1}; storey shear V_i acts as +V_i on floor i and
// -V_i on floor i-1, so r_i = V_i - V_{i+1}.
//
// A large, sparse model is also held compressed (sparse_mass, sparse_damping, sparse_stiffness:
// the same M, C, K, column-major; core/sparse_structure.h says when and why): the explicit
// integrators then step in O(nnz) and the modes come from a sparse eigensolver. The dense
// matrices may then be empty (a model built sparse only, too large to hold densely); every
// function that needs them says so.

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

namespace rths::core {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;
using SparseMat = Eigen::SparseMatrix<double>;

// Modal damping of a model held sparse, kept as factors (core/sparse_structure.h,
// sparse_modal_damping): B diag(c) B^T with B = M Phi (n x m, kg^1/2; Phi the m lowest
// mass-normalised modes, Phi^T M Phi = I) and c (1/s) the modal damping 2 zeta_i omega_i less
// what the sparse part already gives mode i. Never formed n x n; empty when the model has none.
struct LowRankDamping {
  Mat basis;              // B = M Phi, n x m
  Vec coefficients;       // c, m entries >= 0, 1/s
  std::string statement;  // the modes kept and what the others get, printed before a run
  bool empty() const { return coefficients.size() == 0; }
};

struct StructuralModel {
  Mat mass;                              // kg
  Mat damping;                           // N s/m (with low_rank_damping: its sparse part)
  Mat stiffness;                         // N/m (initial, linear)
  Vec influence;                         // iota: 1 for every floor under a horizontal ground motion
  std::vector<double> storey_stiffness;  // N/m, as given
  // The same M, C, K compressed; all three set or none (is_sparse()).
  SparseMat sparse_mass, sparse_damping, sparse_stiffness;
  // Only on a model held sparse: C = sparse_damping + the low-rank term (modal damping through
  // the lowest modes); the explicit sparse integrators step both, the dense schemes refuse it.
  LowRankDamping low_rank_damping;

  // omega_max (rad/s) of this M and K once known (remember_max_omega), so that every simulation
  // of a study reuses one estimate; 0: not known. Whoever changes M or K after it is set resets
  // it to 0.
  double known_max_omega = 0.0;

  bool is_sparse() const { return sparse_mass.rows() > 0; }
  int dofs() const { return static_cast<int>(is_sparse() ? sparse_mass.rows() : mass.rows()); }
};

// Shear building from floor masses (kg) and storey stiffnesses (N/m), no damping yet.
// Throws std::invalid_argument on empty, mismatched or non-positive inputs.
StructuralModel make_shear_building(const std::vector<double>& storey_mass,
                                    const std::vector<double>& storey_stiffness);

// SDOF with period T (s) and mass m (kg): k = m (2 pi / T)^2; damping c = 2 zeta m omega.
StructuralModel make_sdof(double period, double zeta, double mass = 1.0);

// Natural circular frequencies (rad/s), ascending, and mass-normalised mode shapes (columns).
struct Modes {
  Vec omega;
  Mat shapes;
};
Modes modal_analysis(const Mat& mass, const Mat& stiffness);

// C = a0 M + a1 K meeting zeta at modes i and j (1-based); for one DOF, mass-proportional c =
// 2 zeta m omega... equivalently a0 = 2 zeta omega, a1 = 0.
Mat rayleigh_damping(const Mat& mass, const Mat& stiffness, double zeta, int mode_i = 1,
                     int mode_j = 2);
// C = M Phi diag(2 zeta omega_n) Phi^T M: the same ratio in every mode.
Mat modal_damping(const Mat& mass, const Mat& stiffness, double zeta);

// Highest natural circular frequency (rad/s); the explicit integrators' stability limit uses it.
// A dense model's from the dense analysis. A model held sparse: sqrt of the largest Ritz value of
// a plain Lanczos run on M^-1 K in the M inner product (O(nnz) a step, no n x n matrix; the
// tridiagonal's largest eigenvalue by bisection), stopped when it moves by less than 1e-10
// relative over 50 steps (at most 4000 steps). A Ritz value never exceeds the largest
// eigenvalue, so a stable dt is never refused; a 10,000-DOF uniform chain, whose top eigenvalues
// are 1e-8 apart, gets omega_max to ~1e-8 (an unstable dt may pass by that).
// model.known_max_omega when set (> 0), without a new estimate.
double max_omega(const StructuralModel& model);
// Sets model.known_max_omega to a fresh max_omega: once a study's model is final (its split done).
void remember_max_omega(StructuralModel& model);

}  // namespace rths::core
