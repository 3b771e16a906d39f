#pragma once
// Time integrators for M a + C v + r(u, v) = p(t), stepping from t_k to t_{k+1} = t_k + dt.
//
// The restoring force is obtained through a RestoringEvaluator so the same integrator drives an
// in-process model, a delayed experimental substructure, or a node across DDS.
//
//   Integrator          predictor (u_{k+1}, v~_{k+1})                 stability (undamped)
//   EXPLICIT_NEWMARK    u+ = u + dt v + dt^2/2 a;  v~ = v + dt a      omega dt <= 2
//                       (M + dt/2 C) a+ = p+ - r+ - C (v + dt/2 a);  v+ = v + dt/2 (a + a+)
//   CENTRAL_DIFFERENCE  u+ = u + dt v_{k+1/2},  v_{k+1/2} = v_{k-1/2} + dt a_k   omega dt <= 2
//                       v+ = v_{k+1/2} + dt/2 a+ (a+ from equilibrium with that v+)
//   CHEN_RICLES         v+ = v + dt A1 a;  u+ = u + dt v + dt^2 A2 a,  unconditional for linear
//                       A1 = A2 = 4 (4M + 2 dt C + dt^2 K0)^-1 M;      and softening systems
//                       M a+ = p+ - C v+ - r+
//   NEWMARK_AVERAGE_ACC implicit, beta = 1/4, gamma = 1/2, Newton on the tangent;  unconditional
//                       needs repeated trials: refused with a delayed experimental part.
//   ALPHA_OS            alpha-operator splitting (Combescure & Pegon 1997, Nucl. Eng. Des. 168;
//                       as OpenSees AlphaOS), alpha in [2/3, 1], beta = (2 - alpha)^2 / 4,
//                       gamma = 3/2 - alpha. Explicit in displacement: the restoring force is taken
//                       at the predictor u~+ = u + dt v + (1/2 - beta) dt^2 a (what is commanded),
//                       v~+ = v + (1 - gamma) dt a;
//                       [M + alpha gamma dt C + alpha beta dt^2 K0] a+ = f_alpha
//                         - (1 - alpha) (C v + r~ + K0 (u - u~)) - alpha (C v~+ + r~+),
//                       f_alpha = (1 - alpha) f + alpha f+, r~ = r(u~) of the previous step;
//                       u+ = u~+ + beta dt^2 a+, v+ = v~+ + gamma dt a+.
//                       Unconditionally stable for linear elastic (K = K0) and softening
//                       (K_t <= K0) systems; second-order accurate; alpha < 1 adds dissipation.
//   KR_ALPHA            KR-alpha (Kolay & Ricles 2014, Earthquake Engng Struct. Dyn. 43(9); as
//                       OpenSees KRAlphaExplicit), rho_inf in [0, 1]: alpha_m = (2 - rho)/(1 + rho),
//                       alpha_f = 1/(1 + rho), beta = 1/(1 + rho)^2, gamma = (3 - rho)/(2 (1 + rho))
//                       (OpenSees' weights on the new state). D = M + gamma dt C + beta dt^2 K0,
//                       A1 = D^-1 M, A3 = D^-1 [(1 - alpha_m) M + (1 - alpha_f)(gamma dt C +
//                       beta dt^2 K0)], M^ = M (I - A3):
//                       v+ = v + dt A1 a;  u+ = u + dt v + (1/2 + gamma) dt^2 A1 a;
//                       M^ a+ = f_af - M A3 a - C v_af - r_af,  x_af = (1 - alpha_f) x + alpha_f x+
//                       (r+ measured at u+, so r_af = (1 - alpha_f) r + alpha_f r+: equal to r(u_af)
//                       for a linear part). Unconditionally stable for linear elastic and softening
//                       systems; second-order accurate; rho_inf < 1 adds high-frequency dissipation.
//                       Neither needs a dt limit, so neither refuses a dt: they refuse parameters
//                       outside those ranges instead, naming the range.
//   EXACT_ZOH           the structure's linear part K_x integrated exactly over the step (matrix
//                       exponential), the rest of the restoring force (the measured
//                       experimental force) held over it at its value of the step before, the
//                       load linear between samples: core/exact_zoh.h. Exact for a linear
//                       structure without a held part; no dt limit of its own (the held force
//                       is a lag, which the critical-delay analysis judges with the loop).
// v~ is the velocity the integrator has computed when it sends u+; the paper's Eq. 1 uses it.

#include <functional>
#include <memory>
#include <string>

#include "core/integrator.h"
#include "core/structure.h"

namespace rths::core {

std::string to_string(IntegratorKind kind);
IntegratorKind integrator_from_string(const std::string& name);  // throws listing valid names

// Largest stable omega * dt for an undamped linear system (infinity when unconditional).
double stability_limit(IntegratorKind kind);
bool is_explicit(IntegratorKind kind);

// Throws std::invalid_argument naming the integrator, omega_max, dt and the limit when
// omega_max * dt exceeds it, unless `allow_unstable`.
void check_stability(IntegratorKind kind, double omega_max, double dt, bool allow_unstable);

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const StructuralModel& model,
                                            double dt);
// Throws std::invalid_argument naming alpha_os or rho_infinity and its range when out of it.
std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const StructuralModel& model,
                                            double dt, const IntegratorParameters& parameters);

}  // namespace rths::core
