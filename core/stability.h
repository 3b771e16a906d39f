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

}  // namespace rths::core
