#pragma once
// Critical delay of a delayed SDOF hybrid system.
//
// Continuous:  m u'' + c u' + k_n u + k_e u(t - tau) = 0,  k_n = (1 - alpha) k, k_e = alpha k.
//   A root crosses the imaginary axis at s = i w when (k_n - m w^2)^2 + (c w)^2 = k_e^2, i.e.
//   m^2 w^4 + (c^2 - 2 m k_n) w^2 + k_n^2 - k_e^2 = 0, and then
//   e^{-i w tau} = -(k_n - m w^2 + i c w) / k_e  gives  tau_j = (theta + 2 pi j) / w, j = 0, 1, ..
//   with theta in [0, 2 pi). The critical delay is the smallest tau over all crossing branches.
//   No positive w^2 root: stable for every delay.
// Discrete: the explicit/implicit integrator with the experimental force taken at the command of
//   n steps earlier (a time shift of n dt); the first n whose amplification matrix has spectral
//   radius > 1.

#include <optional>
#include <string>
#include <vector>

#include "core/integrators.h"

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
  std::optional<int> first_unstable_steps;    // n; empty if none up to max_steps
  std::optional<double> first_unstable_delay; // n dt, s
  std::vector<double> spectral_radius;        // for n = 0..max_steps (until first unstable + 1)
};

DiscreteStability discrete_critical_delay(IntegratorKind kind, double period, double zeta,
                                          double alpha, double dt, int max_steps);

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
// taken n steps late (discrete_critical_delay, searched up to kMaxDiscreteSteps).
struct CriticalDelayCheck {
  static constexpr int kMaxDiscreteSteps = 120;
  double lag = 0.0;                          // s, the tau checked
  std::optional<double> continuous;          // s; empty: stable for every delay
  std::optional<double> discrete;            // s; empty: none found up to the searched steps
  int discrete_searched_steps = 0;           // n searched for the discrete limit
  int governing_mode = 1;                    // 1-based mode with the smallest continuous delay
  double governing_period = 0.0;             // s
  double governing_fraction = 0.0;           // alpha of that mode
  // The smaller of the two limits (continuous, discrete); empty when neither exists.
  std::optional<double> critical() const;
  bool past() const { return critical() && lag >= *critical(); }
  // (critical - lag) / critical: 0.2 = 20 % below the limit; negative when past it.
  double margin() const;
  // One line: "lag 14 ms against a critical delay of 7.97 ms (continuous; discrete 8 ms at dt =
  // 1 ms): past it by 76 %" or "... 42 % below it".
  std::string describe() const;
};

CriticalDelayCheck check_critical_delay(const StructuralModel& model,
                                        const std::vector<double>& experimental_storey_stiffness,
                                        IntegratorKind kind, double dt, double lag);

}  // namespace rths::core
