#include "core/stability.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace rths::core {
namespace {

struct SdofParameters {
  double m = 1.0, c = 0.0, k_numerical = 0.0, k_experimental = 0.0;
};

SdofParameters sdof_parameters(double period, double zeta, double alpha) {
  if (!(period > 0)) throw std::invalid_argument("stability: period must be > 0 s");
  if (zeta < 0) throw std::invalid_argument("stability: zeta must be >= 0");
  if (!(alpha >= 0 && alpha <= 1)) throw std::invalid_argument("stability: alpha must be in [0, 1]");
  const double omega = 2.0 * std::numbers::pi / period;
  const double k = omega * omega;  // unit mass: the result does not depend on it
  return {1.0, 2.0 * zeta * omega, (1.0 - alpha) * k, alpha * k};
}

// One step of the integrator on the state x = [u, v, a, u_{k-1}, ..., u_{k-n+1}], with the
// experimental force taken at the displacement of n steps earlier. Linear, so its matrix is
// built column by column from unit states.
Vec advance(IntegratorKind kind, const SdofParameters& p, double dt, int n, const Vec& x) {
  const double u = x[0], v = x[1], a = x[2];
  const int history = std::max(n - 1, 0);
  auto delayed = [&](double u_next) {
    if (n == 0) return u_next;
    if (n == 1) return u;
    return x[3 + (n - 2)];  // u_{k+1-n} = h_{n-1}
  };
  double u_next = 0, v_next = 0, a_next = 0;
  switch (kind) {
    case IntegratorKind::kExplicitNewmark:
    case IntegratorKind::kCentralDifference: {  // algebraically identical for this system
      u_next = u + dt * v + 0.5 * dt * dt * a;
      const double r = p.k_numerical * u_next + p.k_experimental * delayed(u_next);
      a_next = (-r - p.c * (v + 0.5 * dt * a)) / (p.m + 0.5 * dt * p.c);
      v_next = v + 0.5 * dt * (a + a_next);
      break;
    }
    case IntegratorKind::kChenRicles: {
      const double k0 = p.k_numerical + p.k_experimental;
      const double alpha = 4.0 * p.m / (4.0 * p.m + 2.0 * dt * p.c + dt * dt * k0);
      v_next = v + dt * alpha * a;
      u_next = u + dt * v + dt * dt * alpha * a;
      const double r = p.k_numerical * u_next + p.k_experimental * delayed(u_next);
      a_next = (-p.c * v_next - r) / p.m;
      break;
    }
    case IntegratorKind::kNewmarkAverageAcceleration: {
      // Undelayed stiffness is implicit; a delayed experimental force is known from history.
      const double k_implicit = p.k_numerical + (n == 0 ? p.k_experimental : 0.0);
      const double explicit_force = n == 0 ? 0.0 : p.k_experimental * delayed(0.0);
      const double predictor = u + dt * v + 0.25 * dt * dt * a;
      a_next = (-p.c * (v + 0.5 * dt * a) - k_implicit * predictor - explicit_force) /
               (p.m + 0.5 * dt * p.c + 0.25 * dt * dt * k_implicit);
      u_next = predictor + 0.25 * dt * dt * a_next;
      v_next = v + 0.5 * dt * (a + a_next);
      break;
    }
  }
  Vec next = Vec::Zero(3 + history);
  next[0] = u_next;
  next[1] = v_next;
  next[2] = a_next;
  if (history > 0) {
    next[3] = u;
    for (int j = 1; j < history; ++j) next[3 + j] = x[3 + j - 1];
  }
  return next;
}

double spectral_radius(IntegratorKind kind, const SdofParameters& p, double dt, int n) {
  const int size = 3 + std::max(n - 1, 0);
  Mat amplification(size, size);
  for (int j = 0; j < size; ++j) {
    amplification.col(j) = advance(kind, p, dt, n, Vec::Unit(size, j));
  }
  Eigen::EigenSolver<Mat> solver(amplification, false);
  return solver.eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace

ContinuousStability continuous_critical_delay(double period, double zeta, double alpha,
                                              int branches) {
  const SdofParameters p = sdof_parameters(period, zeta, alpha);
  ContinuousStability result;
  result.stable_without_delay = p.c > 0 && p.k_numerical + p.k_experimental > 0;
  if (p.k_experimental == 0.0) {
    result.stable_for_all_delays = result.stable_without_delay;
    return result;
  }
  // m^2 x^2 + (c^2 - 2 m k_n) x + (k_n^2 - k_e^2) = 0 with x = w^2.
  const double qa = p.m * p.m;
  const double qb = p.c * p.c - 2.0 * p.m * p.k_numerical;
  const double qc = p.k_numerical * p.k_numerical - p.k_experimental * p.k_experimental;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  std::vector<double> omega_squared;
  if (discriminant >= 0) {
    const double root = std::sqrt(discriminant);
    for (double x : {(-qb + root) / (2.0 * qa), (-qb - root) / (2.0 * qa)}) {
      if (x > 0 && std::find(omega_squared.begin(), omega_squared.end(), x) == omega_squared.end()) {
        omega_squared.push_back(x);
      }
    }
  }
  for (double x : omega_squared) {
    const double w = std::sqrt(x);
    const std::complex<double> z =
        -std::complex<double>(p.k_numerical - p.m * x, p.c * w) / p.k_experimental;
    // e^{-i w tau} = z  =>  w tau = -arg(z) mod 2 pi.
    double phase = std::fmod(-std::arg(z), 2.0 * std::numbers::pi);
    if (phase < 0) phase += 2.0 * std::numbers::pi;
    for (int j = 0; j < branches; ++j) {
      result.crossings.push_back({w, (phase + 2.0 * std::numbers::pi * j) / w, j});
    }
  }
  std::sort(result.crossings.begin(), result.crossings.end(),
            [](const DelayCrossing& l, const DelayCrossing& r) { return l.delay < r.delay; });
  result.stable_for_all_delays = result.stable_without_delay && result.crossings.empty();
  if (!result.crossings.empty() && result.stable_without_delay) {
    result.critical_delay = result.crossings.front().delay;
  } else if (!result.stable_without_delay) {
    result.critical_delay = 0.0;
  }
  return result;
}

DiscreteStability discrete_critical_delay(IntegratorKind kind, double period, double zeta,
                                          double alpha, double dt, int max_steps) {
  if (!(dt > 0)) throw std::invalid_argument("stability: dt must be > 0 s");
  if (max_steps < 0) throw std::invalid_argument("stability: max_steps must be >= 0");
  const SdofParameters p = sdof_parameters(period, zeta, alpha);
  DiscreteStability result;
  constexpr double kGrowthTolerance = 1e-9;  // spectral radius above 1 + this grows
  for (int n = 0; n <= max_steps; ++n) {
    const double rho = spectral_radius(kind, p, dt, n);
    result.spectral_radius.push_back(rho);
    if (rho > 1.0 + kGrowthTolerance) {
      result.first_unstable_steps = n;
      result.first_unstable_delay = n * dt;
      break;
    }
  }
  return result;
}

std::optional<double> CriticalDelayCheck::critical() const {
  if (continuous && discrete) return std::min(*continuous, *discrete);
  if (continuous) return continuous;
  return discrete;
}

double CriticalDelayCheck::margin() const {
  const auto limit = critical();
  if (!limit || *limit <= 0.0) return limit ? -1.0 : 1.0;
  return (*limit - lag) / *limit;
}

std::string CriticalDelayCheck::describe() const {
  std::ostringstream out;
  out.precision(3);
  out << "lag " << lag * 1e3 << " ms";
  const auto limit = critical();
  if (!limit) {
    out << ": stable for every delay (continuous; discrete none up to " << discrete_searched_steps
        << " steps)";
    return out.str();
  }
  out << " against a critical delay of " << *limit * 1e3 << " ms (continuous ";
  if (continuous) out << *continuous * 1e3 << " ms"; else out << "none";
  out << ", discrete ";
  if (discrete) out << *discrete * 1e3 << " ms"; else out << "none up to " << discrete_searched_steps << " steps";
  out << "; mode " << governing_mode << ", T = " << governing_period << " s, experimental fraction "
      << governing_fraction << "): ";
  const double m = margin();
  if (m < 0) out << "PAST it by " << -m * 100.0 << " %";
  else out << m * 100.0 << " % below it";
  return out.str();
}

CriticalDelayCheck check_critical_delay(const StructuralModel& model,
                                        const std::vector<double>& experimental_storey_stiffness,
                                        IntegratorKind kind, double dt, double lag) {
  if (!(dt > 0)) throw std::invalid_argument("critical delay check: dt must be > 0 s");
  const int dofs = model.dofs();
  if (static_cast<int>(experimental_storey_stiffness.size()) != dofs) {
    throw std::invalid_argument("critical delay check: one experimental stiffness per storey expected");
  }
  // K_e of a shear building from the storeys' experimental stiffnesses.
  Mat k_experimental = Mat::Zero(dofs, dofs);
  for (int s = 0; s < dofs; ++s) {
    const double k = experimental_storey_stiffness[static_cast<std::size_t>(s)];
    k_experimental(s, s) += k;
    if (s > 0) {
      k_experimental(s - 1, s - 1) += k;
      k_experimental(s - 1, s) -= k;
      k_experimental(s, s - 1) -= k;
    }
  }
  const Modes modes = modal_analysis(model.mass, model.stiffness);
  CriticalDelayCheck check;
  check.lag = lag;
  const int lag_steps = lag > 0 ? static_cast<int>(std::ceil(lag / dt - 1e-9)) : 0;
  check.discrete_searched_steps = std::min(lag_steps + 1, CriticalDelayCheck::kMaxDiscreteSteps);
  for (int i = 0; i < dofs; ++i) {
    const double omega = modes.omega[i];
    const Vec phi = modes.shapes.col(i);
    const double zeta = phi.dot(model.damping * phi) / (2.0 * omega);
    const double alpha = std::clamp(phi.dot(k_experimental * phi) / (omega * omega), 0.0, 1.0);
    const double period = 2.0 * std::numbers::pi / omega;
    const ContinuousStability continuous = continuous_critical_delay(period, zeta, alpha);
    if (continuous.critical_delay && (!check.continuous || *continuous.critical_delay < *check.continuous)) {
      check.continuous = continuous.critical_delay;
      check.governing_mode = i + 1;
      check.governing_period = period;
      check.governing_fraction = alpha;
    }
    if (i == 0 && !check.continuous) {
      check.governing_period = period;
      check.governing_fraction = alpha;
    }
    const DiscreteStability discrete =
        discrete_critical_delay(kind, period, zeta, alpha, dt, check.discrete_searched_steps);
    if (discrete.first_unstable_delay && (!check.discrete || *discrete.first_unstable_delay < *check.discrete)) {
      check.discrete = discrete.first_unstable_delay;
    }
  }
  return check;
}

}  // namespace rths::core
