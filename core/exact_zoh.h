#pragma once
// A linear structure integrated exactly over each step, with the rest of the restoring force (the
// measured experimental force) held over the step: how a continuous-time model of a hybrid test
// integrates it. The RTHS benchmark's Simulink model (Silva et al. 2020) does so: its numerical
// substructure is a continuous state space stepped by ode4 at 4096 Hz, and the feedback force
// reaches it through a Unit Delay, so it is constant over each step.
//
// Block ExactDiscretisation (no state; matrices computed once):
//   continuous   M u'' + C u' + K u = w(t),  x = [u; v] (m, m/s),  w (N per DOF)
//                x' = A x + B w,  A = [0 I; -M^-1 K  -M^-1 C],  B = [0; M^-1]
//   one step h with w linear over it, w(t_k + s) = w_k + (w_{k+1} - w_k) s / h:
//                x_{k+1} = Phi x_k + Gamma0 w_k + Gamma1 (w_{k+1} - w_k)
//                Phi = e^{A h},  Gamma0 = int_0^h e^{A s} ds B,
//                Gamma1 = (1/h) int_0^h e^{A (h - s)} s ds B
//   (w_{k+1} = w_k: a zero-order hold), all three from one matrix exponential (Van Loan):
//                exp([A B 0; 0 0 I/h; 0 0 0] h) = [Phi Gamma0 Gamma1; 0 I I; 0 0 I].
//
// Block ExactZohIntegrator (IntegratorKind::kExactZoh; state u, v, a, the held force h_k and the
// load p_k of the step before):
//   input  p_{k+1} (N per DOF, the ground load), the restoring evaluator r(u, v) (N per DOF)
//   output u_{k+1} (m), v_{k+1} (m/s), a_{k+1} (m/s^2)
//   K_x the linear stiffness integrated exactly (N/m; a hybrid run's numerical part K - K_e),
//   h = r - K_x u the rest of the restoring force (the measured experimental force, and what a
//   nonlinear numerical part adds to K_x u), held at its value of the step before; the ground
//   load linear between its samples (as the exact reference response takes it):
//     x_{k+1} = Phi x_k + Gamma0 (p_k - h_k) + Gamma1 (p_{k+1} - p_k)     (w = p - h)
//     r_{k+1} = restoring.trial(u_{k+1}, v_{k+1});  h_{k+1} = r_{k+1} - K_x u_{k+1}
//     a_{k+1} = M^-1 (p_{k+1} - C v_{k+1} - r_{k+1})
//   Exact, for any dt, when the whole restoring force is K_x u (h = 0); the held force lags by
//   one step, a lag the loop's stability sees as a delay (core/stability.h models it: a stiff
//   held part at a coarse dt is unstable without any other delay). The restoring force is asked
//   once per step, so it runs with a delayed or remote experimental part.

#include <memory>

#include "core/integrator.h"

namespace rths::core {

struct ExactDiscretisation {
  Mat phi;     // 2n x 2n
  Mat gamma0;  // 2n x n, (m, m/s) per N
  Mat gamma1;  // 2n x n
};

// @pre M symmetric positive definite, square matrices of one size n, h > 0 (s).
ExactDiscretisation exact_discretisation(const Mat& mass, const Mat& damping, const Mat& stiffness,
                                         double h);

// `exact_stiffness` is K_x (n x n, N/m). Throws std::invalid_argument when its size is not the
// model's or dt is not > 0.
std::unique_ptr<Integrator> make_exact_zoh_integrator(const StructuralModel& model, double dt,
                                                      const Mat& exact_stiffness);

}  // namespace rths::core
