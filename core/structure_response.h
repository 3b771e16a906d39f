#pragma once
// The exact response of a linear structure, the yardstick a hybrid run is judged against.
//
//   M a + C v + K u = -M iota a_g(t),  u, v, a relative to the ground (m, m/s, m/s^2)
//   state x = [u; v]:  x' = A x + B a_g,  A = [0 I; -M^-1 K  -M^-1 C],  B = [0; -iota]
// The ground acceleration is taken linear between its samples (first-order hold), for which the
// discrete solution is exact:
//   x_{k+1} = Phi x_k + G0 a_k + G1 (a_{k+1} - a_k) / dt,
//   Phi = e^{A dt}, G0 = int_0^dt e^{A r} dr B, G1 = int_0^dt e^{A r} (dt - r) dr B,
// all three read from one matrix exponential (Van Loan): exp([A B 0; 0 0 I; 0 0 0] dt).
// a_k = -M^-1 (K u_k + C v_k) - iota a_g,k. Starts at rest. Input: the motion at dt (m/s^2).
// Output: rows = samples of the motion, columns = DOFs.

#include "core/ground_motion.h"
#include "core/structure.h"

namespace rths::core {

struct LinearResponse {
  double dt = 0.0;  // s
  Mat displacement, velocity, acceleration;
};

// @pre the model's matrices pass check_structural_matrices (study/structure_io.h); dt = motion's.
LinearResponse exact_linear_response(const StructuralModel& model, const GroundMotion& motion);

}  // namespace rths::core
