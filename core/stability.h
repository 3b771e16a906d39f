#pragma once
// Critical delay of a delayed SDOF hybrid system.
//
// Continuous:  m u'' + c u' + k_n u + k_e u(t - tau) = 0,  k_n = (1 - alpha) k, k_e = alpha k.
//   A root crosses the imaginary axis at s = i w when (k_n - m w^2)^2 + (c w)^2 = k_e^2, i.e.
//   m^2 w^4 + (c^2 - 2 m k_n) w^2 + k_n^2 - k_e^2 = 0, and then
//   e^{-i w tau} = -(k_n - m w^2 + i c w) / k_e  gives  tau_j = (theta + 2 pi j) / w, j = 0, 1, ..
//   with theta in [0, 2 pi). The critical delay is the smallest tau over all crossing branches.
//   No positive w^2 root: stable for every delay.
// Compensated loop (the experimental force is k_e x_m, x_m = H(s) e^{-s delta} u: H the loop's
//   blocks, compensator C then actuator stages G, each stating its own linear dynamics
//   (core/linear_dynamics.h), and an extra, unmodelled delay delta the analysis searches for):
//   continuous (continuous_loop_crossings): m s^2 + c s + k_n + k_e H(s) e^{-s delta} = 0,
//     H = G C. A root crosses at s = i w when |k_n - m w^2 + i c w| = k_e |H(i w)|, solved
//     numerically (sign changes on a log grid of 20000 w from 1e-3 sqrt((k_n + k_e) / m) up to
//     the Nyquist frequency pi / dt, each refined by 100 bisections; no closed form once H is not
//     a pure delay), then e^{-i w delta} = -(k_n - m w^2 + i c w) / (k_e H(i w)) gives
//     delta_j = (theta + 2 pi j) / w. The delay margin is the smallest delta_j. Without a
//     compensator and with G a pure shift tau it is continuous_critical_delay() - tau.
//   discrete (discrete_loop_stability): one step of the integrator on the state [u, v, a, z], z
//     the states of the loop's realisation (LinearDynamics::state_space) in series with the extra
//     delay (a shift_block: a fractional delay interpolates between two register taps, as
//     TimeShift does); the amplification matrix is built column by column from unit states. The
//     margin is the first integer step count whose spectral radius exceeds 1 + 1e-9, refined by
//     30 bisections on the fractional delay. Stability at zero extra delay is judged here (the
//     continuous search assumes it). Implicit integrators are refused (the delayed loop is
//     explicit). A block that adapts (ATS) enters frozen at its present coefficients (its
//     Linearity note says so): the linear analysis cannot follow its adaptation.
//   A loop with a block that cannot be represented (Linearity kNone: a jitter or trace stage,
//   the velocity-reading Eq1 stages) is refused with std::invalid_argument naming the block.
//
// Discrete: the explicit/implicit integrator with the experimental force taken at the command of
//   n steps earlier (a time shift of n dt); the first n whose amplification matrix has spectral
//   radius > 1. EXACT_ZOH on the state [u, v, a]: the force it holds over the step is
//   r - k_N u = -(m a + c v + k_N u) of the step before (its equilibrium), so its step is
//   [u, v]+ = Phi [u, v] - Gamma0 (that force) (core/exact_zoh.h), then a+ from equilibrium.

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "core/delay.h"
#include "core/integrators.h"
#include "core/linear_dynamics.h"
#include "core/structure.h"

namespace rths::core {

struct DelayCrossing {
  double omega = 0.0;  // rad/s at the crossing
  double delay = 0.0;  // s
  int branch = 0;      // j above
};

struct ContinuousStability {
  bool stable_without_delay = false;
  bool stable_for_all_delays = false;
  std::vector<DelayCrossing> crossings;  // ascending delay, `branches` per frequency
  std::optional<double> critical_delay;  // s; empty when stable for all delays
};

ContinuousStability continuous_critical_delay(double period, double zeta, double alpha,
                                              int branches = 3);

struct DiscreteStability {
  std::optional<int> first_unstable_steps;     // n; empty if none up to max_steps
  std::optional<double> first_unstable_delay;  // n dt, s
  std::vector<double> spectral_radius;         // for n = 0..max_steps (until first unstable + 1)
};

DiscreteStability discrete_critical_delay(IntegratorKind kind, double period, double zeta,
                                          double alpha, double dt, int max_steps);

struct LoopDiscreteStability {
  bool stable = false;           // at zero extra delay
  double spectral_radius = 0.0;  // at zero extra delay
  std::optional<double> margin;  // extra delay (s); empty: stable up to max_extra_delay
};
// @pre an explicit integrator, dt > 0, max_extra_delay >= 0, `loop` analysable.
LoopDiscreteStability discrete_loop_stability(IntegratorKind kind, double period, double zeta,
                                              double alpha, double dt, const LinearDynamics& loop,
                                              double max_extra_delay);

struct LoopContinuousStability {
  std::vector<DelayCrossing> crossings;  // extra-delay crossings, ascending, `branches` each
  std::optional<double> margin;          // s; empty: no crossing
};
// @pre dt > 0 (it bounds the search at pi / dt), `loop` analysable.
LoopContinuousStability continuous_loop_crossings(double period, double zeta, double alpha,
                                                  double dt, const LinearDynamics& loop,
                                                  int branches = 3);

struct CompensatedStability {
  // Discrete, at zero extra delay.
  bool stable = false;
  double spectral_radius = 0.0;
  // Extra delay (s) the loop tolerates before it grows: continuous and discrete.
  std::optional<double> continuous_margin;  // empty: no crossing (stable for every extra delay)
  std::vector<DelayCrossing> crossings;     // extra-delay crossings, ascending
  std::optional<double> discrete_margin;    // empty: stable up to max_extra_delay
  double max_extra_delay = 0.0;             // s, discrete search range
  // Non-empty when the compensator adapts online (ATS, model-based with adaptive_correction):
  // the loop is time-varying and has no fixed amplification matrix; everything above is the
  // frozen-coefficient analysis at the initial coefficients, which this text states. It is exact
  // until the first fit (one window) and, for a correction that learns extra delay as model
  // error, conservative after it (tests/core/stability_test.cpp measures both).
  std::string frozen_coefficients;
  // Non-empty when a block was linearised (a tracking loop's converters left out): which.
  std::string linearised;
};

// Both analyses of `loop` (its compensator, if any, then its stages). @pre as above.
CompensatedStability compensated_stability(IntegratorKind kind, double period, double zeta,
                                           double alpha, double dt, const DelayChain& loop,
                                           double max_extra_delay, int branches = 3);
// The same loop simulated: an SDOF after a one-step ground pulse, free vibration through `loop`;
// returns peak |u| over the last third of the run divided by that over the first third (> 1 grows,
// < 1 decays).
double simulated_growth(IntegratorKind kind, double period, double zeta, double alpha, double dt,
                        DelayChain loop, double duration);

// Pre-run check of a hybrid setup against the lag its delay stages add.
//
// Inputs: the structure (M, C, K; SI), the experimental stiffness of each storey (N/m, 0 where a
// storey is wholly numerical), the integrator and its step dt (s), and the lag tau (s): the
// chain's low-frequency delay (negative = lead, which adds damping and is never past).
// Each mode i of (M, K) is taken as an SDOF: period T_i, damping ratio zeta_i = phi_i' C phi_i /
// (2 omega_i) and experimental fraction alpha_i = phi_i' K_e phi_i / omega_i^2 (mass-normalised
// phi). For an SDOF this is exact; for several storeys it is the modal approximation (it ignores
// the coupling between modes that the delayed force adds). The critical delays are the smallest
// over modes: continuous (continuous_critical_delay) and discrete, the integrator with the force
// taken n steps late (discrete_critical_delay, searched up to kMaxDiscreteSteps). Where the modes
// do not diagonalise K_e and C (whole storeys, elements between DOFs, a specimen at one DOF), the
// continuous limit is the coupled analysis' (core/coupled_stability.h: every experimental part at
// the same lag, the delayed force's coupling between modes included) and modal_continuous keeps
// the modal approximation's.
struct CriticalDelayCheck {
  static constexpr int kMaxDiscreteSteps = 120;
  double lag = 0.0;                  // s, the tau checked
  std::optional<double> continuous;  // s; empty: stable for every delay
  // The continuous limit is the coupled analysis' (the modes do not decouple K_e and C), and
  // modal_continuous (s) the modal approximation's it replaced.
  bool coupled = false;
  std::optional<double> modal_continuous;
  std::optional<double> discrete;   // s; empty: none found up to the searched steps
  int discrete_searched_steps = 0;  // n searched for the discrete limit
  // Why the discrete limit was not searched (the integrator is outside the discrete analysis:
  // alpha-os, kr-alpha); empty when it was. The run goes ahead on the continuous limit alone.
  std::string discrete_skipped;
  std::string assumed;              // what the check assumed (modal approximation...)
  int governing_mode = 1;           // 1-based mode with the smallest continuous delay
  double governing_period = 0.0;    // s
  double governing_fraction = 0.0;  // alpha of that mode
  // The smaller of the two limits (continuous, discrete); empty when neither exists.
  std::optional<double> critical() const;
  bool past() const { return critical() && lag >= *critical(); }
  // (critical - lag) / critical: 0.2 = 20 % below the limit; negative when past it.
  double margin() const;
  // One line: "lag 14 ms against a critical delay of 7.97 ms (continuous 7.97 ms, discrete 8 ms;
  // mode 1, ...): PAST it by 76 %" or "... 42 % below it"; "continuous (coupled) ..." where the
  // coupled analysis gave it.
  std::string describe() const;
  // Sets the governing mode to the one of `modes` whose omega_i (rad/s) is nearest `omega`
  // (rad/s), a coupled analysis' crossing: its 1-based index, period 2 pi / omega_i (s) and
  // fraction alpha_i = phi_i' K_e phi_i / omega_i^2, clamped to [0, 1].
  void govern_by_mode_nearest(double omega, const Modes& modes, const SparseMat& k_experimental);
};

// The loop compensated by a Smith predictor on the force (core/force_predictor.h) whose model is
// off: with a model k_m = (1 + stiffness_error) k_e, c_m = damping_error 2 omega_n m (the
// specimen's own damping taken as 0, as the studies declare it; omega_n = 2 pi / period, m = 1),
// the integrator sees k_m u + c_m v + (k_e - k_m) u(t - D) - c_m v(t - D), D the lag of the
// measured pair (round trip plus actuator lag), so the loop is
//   m s^2 + (c + c_m) s + k_n + k_m + (dk + dc s) e^{-s D} = 0,  dk = k_e - k_m, dc = -c_m.
// A root crosses at s = i w when |k_n + k_m - m w^2 + i (c + c_m) w| = |dk + i dc w|:
//   m^2 x^2 + ((c + c_m)^2 - dc^2 - 2 m (k_n + k_m)) x + (k_n + k_m)^2 - dk^2 = 0,  x = w^2,
// then e^{-i w D} = -(k_n + k_m - m w^2 + i (c + c_m) w) / (dk + i dc w) gives D_j. The right
// model (dk = dc = 0) is stable for every lag; so is any model whose error's magnitude stays
// below the loop's own dynamic stiffness at every frequency (about |dk| < c omega_n for light
// damping). The model is frozen at its error: the online fit only shrinks dk with time.
// Continuous time: the integrator's own discretisation is not in it (it is small at dt << T).
ContinuousStability predictor_critical_delay(double period, double zeta, double alpha,
                                             double stiffness_error, double damping_error,
                                             int branches = 3);

// False for the integrators the discrete delay analysis does not model (alpha-os, kr-alpha).
bool discrete_analysis_covers(IntegratorKind kind);

CriticalDelayCheck check_critical_delay(const StructuralModel& model,
                                        const std::vector<double>& experimental_storey_stiffness,
                                        IntegratorKind kind, double dt, double lag);
// The same with K_e given as a matrix (N/m, n x n): a structure given by matrices, whose
// experimental parts sit at DOFs (HybridPartition::experimental_stiffness()).
// K_e held sparse: O(nnz) per mode, so a large model's check forms no n x n matrix.
CriticalDelayCheck check_modal_critical_delay(const StructuralModel& model,
                                              const SparseMat& k_experimental, IntegratorKind kind,
                                              double dt, double lag);
inline CriticalDelayCheck check_modal_critical_delay(const StructuralModel& model,
                                                     const Mat& k_experimental, IntegratorKind kind,
                                                     double dt, double lag) {
  return check_modal_critical_delay(model, SparseMat(k_experimental.sparseView()), kind, dt, lag);
}

}  // namespace rths::core
