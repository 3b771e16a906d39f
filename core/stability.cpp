#include "core/stability.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "core/compensator.h"
#include "core/coupled_stability.h"
#include "core/exact_zoh.h"
#include "core/number_text.h"
#include "core/simulation.h"
#include "core/sparse_structure.h"
#include "core/time_text.h"

namespace rths::core {
namespace {

struct SdofParameters {
  double m = 1.0, c = 0.0, k_numerical = 0.0, k_experimental = 0.0;
};

// EXACT_ZOH's step matrices for the numerical part (m, c, k_numerical) at dt. The searches call
// the step thousands of times with the same parameters: the last ones are kept (per thread).
const ExactDiscretisation& exact_step(const SdofParameters& p, double dt) {
  thread_local std::array<double, 4> key{-1.0, -1.0, -1.0, -1.0};
  thread_local ExactDiscretisation step;
  const std::array<double, 4> wanted{p.m, p.c, p.k_numerical, dt};
  if (wanted != key) {
    step = exact_discretisation(Mat::Constant(1, 1, p.m), Mat::Constant(1, 1, p.c),
                                Mat::Constant(1, 1, p.k_numerical), dt);
    key = wanted;
  }
  return step;
}

SdofParameters sdof_parameters(double period, double zeta, double alpha) {
  if (!(period > 0)) throw std::invalid_argument("stability: period must be > 0 s");
  if (zeta < 0) throw std::invalid_argument("stability: zeta must be >= 0");
  if (!(alpha >= 0 && alpha <= 1))
    throw std::invalid_argument("stability: alpha must be in [0, 1]");
  const double omega = 2.0 * std::numbers::pi / period;
  const double k = omega * omega;  // unit mass: the result does not depend on it
  return {1.0, 2.0 * zeta * omega, (1.0 - alpha) * k, alpha * k};
}

// One step of the explicit schemes both delay analyses cover, for an SDOF of unit mass whose
// restoring force at the predicted displacement is r(u_{k+1}). False for any other integrator.
template <class RestoringForce>
bool explicit_sdof_step(IntegratorKind kind, const SdofParameters& p, double dt, double u, double v,
                        double a, RestoringForce&& r, double& u_next, double& v_next,
                        double& a_next) {
  switch (kind) {
    case IntegratorKind::kExplicitNewmark:
    case IntegratorKind::kCentralDifference:  // algebraically identical for this system
      u_next = u + dt * v + 0.5 * dt * dt * a;
      a_next = (-r(u_next) - p.c * (v + 0.5 * dt * a)) / (p.m + 0.5 * dt * p.c);
      v_next = v + 0.5 * dt * (a + a_next);
      return true;
    case IntegratorKind::kChenRicles: {
      const double k0 = p.k_numerical + p.k_experimental;
      const double alpha = 4.0 * p.m / (4.0 * p.m + 2.0 * dt * p.c + dt * dt * k0);
      v_next = v + dt * alpha * a;
      u_next = u + dt * v + dt * dt * alpha * a;
      a_next = (-p.c * v_next - r(u_next)) / p.m;
      return true;
    }
    case IntegratorKind::kExactZoh: {
      // The force held over the step, r - k_numerical u of the step before, from its equilibrium.
      const ExactDiscretisation& d = exact_step(p, dt);
      const double held = -(p.m * a + p.c * v + p.k_numerical * u);
      u_next = d.phi(0, 0) * u + d.phi(0, 1) * v - d.gamma0(0, 0) * held;
      v_next = d.phi(1, 0) * u + d.phi(1, 1) * v - d.gamma0(1, 0) * held;
      a_next = (-p.c * v_next - r(u_next)) / p.m;
      return true;
    }
    default: return false;
  }
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
  const auto restoring = [&](double u_plus) {
    return p.k_numerical * u_plus + p.k_experimental * delayed(u_plus);
  };
  switch (kind) {
    case IntegratorKind::kExplicitNewmark:
    case IntegratorKind::kCentralDifference:
    case IntegratorKind::kChenRicles:
    case IntegratorKind::kExactZoh:
      explicit_sdof_step(kind, p, dt, u, v, a, restoring, u_next, v_next, a_next);
      break;
    case IntegratorKind::kAlphaOS:
    case IntegratorKind::kKRAlpha:
      throw std::invalid_argument("stability: the discrete delay analysis does not cover " +
                                  to_string(kind) + " yet");
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

namespace {

// The delays at which a characteristic root crosses the imaginary axis at frequency w (rad/s),
// where e^{-i w tau} = z: w tau = -arg(z) mod 2 pi, on `branches` branches.
void add_crossings(ContinuousStability& result, double w, std::complex<double> z, int branches) {
  double phase = std::fmod(-std::arg(z), 2.0 * std::numbers::pi);
  if (phase < 0) phase += 2.0 * std::numbers::pi;
  for (int j = 0; j < branches; ++j)
    result.crossings.push_back({w, (phase + 2.0 * std::numbers::pi * j) / w, j});
}

// Crossings sorted by delay; the critical delay is the first when the loop is stable without
// delay, 0 when it is not.
void settle_critical_delay(ContinuousStability& result) {
  std::sort(result.crossings.begin(), result.crossings.end(),
            [](const DelayCrossing& l, const DelayCrossing& r) { return l.delay < r.delay; });
  result.stable_for_all_delays = result.stable_without_delay && result.crossings.empty();
  if (!result.crossings.empty() && result.stable_without_delay) {
    result.critical_delay = result.crossings.front().delay;
  } else if (!result.stable_without_delay) {
    result.critical_delay = 0.0;
  }
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
      if (x > 0 &&
          std::find(omega_squared.begin(), omega_squared.end(), x) == omega_squared.end()) {
        omega_squared.push_back(x);
      }
    }
  }
  for (double x : omega_squared) {
    const double w = std::sqrt(x);
    const std::complex<double> z =
        -std::complex<double>(p.k_numerical - p.m * x, p.c * w) / p.k_experimental;
    add_crossings(result, w, z, branches);
  }
  settle_critical_delay(result);
  return result;
}

ContinuousStability predictor_critical_delay(double period, double zeta, double alpha,
                                             double stiffness_error, double damping_error,
                                             int branches) {
  if (!(1.0 + stiffness_error >= 0) || !std::isfinite(stiffness_error))
    throw std::invalid_argument("stability: the model's stiffness error must be >= -1, got " +
                                std::to_string(stiffness_error));
  if (!(damping_error >= 0) || !std::isfinite(damping_error))
    throw std::invalid_argument("stability: the model's damping ratio must be >= 0, got " +
                                std::to_string(damping_error));
  const SdofParameters p = sdof_parameters(period, zeta, alpha);
  const double omega_n = 2.0 * std::numbers::pi / period;
  const double k_model = (1.0 + stiffness_error) * p.k_experimental;
  const double c_model = 2.0 * damping_error * omega_n * p.m;
  const double k_fast = p.k_numerical + k_model, c_fast = p.c + c_model;
  const double dk = p.k_experimental - k_model, dc = -c_model;
  ContinuousStability result;
  result.stable_without_delay = p.c > 0 && p.k_numerical + p.k_experimental > 0;
  if (dk == 0.0 && dc == 0.0) {
    result.stable_for_all_delays = result.stable_without_delay;
    return result;
  }
  const double qa = p.m * p.m;
  const double qb = c_fast * c_fast - dc * dc - 2.0 * p.m * k_fast;
  const double qc = k_fast * k_fast - dk * dk;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  std::vector<double> omega_squared;
  if (discriminant >= 0) {
    const double root = std::sqrt(discriminant);
    for (double x : {(-qb + root) / (2.0 * qa), (-qb - root) / (2.0 * qa)})
      if (x > 0 && std::find(omega_squared.begin(), omega_squared.end(), x) == omega_squared.end())
        omega_squared.push_back(x);
  }
  for (double x : omega_squared) {
    const double w = std::sqrt(x);
    const std::complex<double> z =
        -std::complex<double>(k_fast - p.m * x, c_fast * w) / std::complex<double>(dk, dc * w);
    add_crossings(result, w, z, branches);
  }
  settle_critical_delay(result);
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

// ---------------------------------------------------------------------------------------------
// Compensated loop.

namespace {

// One step of an explicit integrator with the experimental force k_e y, y the output of `loop`
// driven by the predicted displacement u_{k+1}. State [u, v, a, z].
Vec advance_loop(IntegratorKind kind, const SdofParameters& p, double dt, const LinearBlock& loop,
                 const Vec& x) {
  const int n = loop.states();
  const double u = x[0], v = x[1], a = x[2];
  const Vec z = x.tail(n);
  double u_next = 0, v_next = 0, a_next = 0;
  Vec next(3 + n);
  const auto force = [&](double u_plus) {
    const double measured = (n > 0 ? loop.c.dot(z) : 0.0) + loop.d * u_plus;
    if (n > 0) next.tail(n) = loop.a * z + loop.b * u_plus;
    return p.k_numerical * u_plus + p.k_experimental * measured;
  };
  if (!explicit_sdof_step(kind, p, dt, u, v, a, force, u_next, v_next, a_next))
    throw std::invalid_argument(
        "stability: the compensated loop needs an explicit integrator, not " + to_string(kind));
  next[0] = u_next;
  next[1] = v_next;
  next[2] = a_next;
  return next;
}

double loop_spectral_radius(IntegratorKind kind, const SdofParameters& p, double dt,
                            const LinearBlock& loop) {
  const int size = 3 + loop.states();
  Mat amplification(size, size);
  for (int j = 0; j < size; ++j)
    amplification.col(j) = advance_loop(kind, p, dt, loop, Vec::Unit(size, j));
  Eigen::EigenSolver<Mat> solver(amplification, false);
  return solver.eigenvalues().cwiseAbs().maxCoeff();
}

void require_loop_inputs(double dt, const LinearDynamics& loop) {
  if (!(dt > 0)) throw std::invalid_argument("stability: dt must be > 0 s");
  const Linearity linearity = loop.linearity();
  if (!linearity.analysable())
    throw std::invalid_argument("stability: " + linearity.note +
                                "; the analysis represents linear blocks only");
}

// The root of f between lo and hi (f(lo) = f_lo and f(hi) differ in sign), by bisection.
template <class F>
double bisect_sign_change(const F& f, double lo, double hi, double f_lo) {
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    const double fm = f(mid);
    if ((fm < 0) == (f_lo < 0)) {
      lo = mid;
      f_lo = fm;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace

LoopDiscreteStability discrete_loop_stability(IntegratorKind kind, double period, double zeta,
                                              double alpha, double dt, const LinearDynamics& loop,
                                              double max_extra_delay) {
  require_loop_inputs(dt, loop);
  if (!(max_extra_delay >= 0))
    throw std::invalid_argument("stability: max_extra_delay must be >= 0 s");
  const SdofParameters p = sdof_parameters(period, zeta, alpha);
  const LinearBlock chain = loop.state_space();
  constexpr double kGrowthTolerance = 1e-9;
  const auto radius = [&](double extra) {
    return loop_spectral_radius(kind, p, dt, series(chain, shift_block(extra, dt)));
  };
  LoopDiscreteStability out;
  out.spectral_radius = radius(0.0);
  out.stable = out.spectral_radius <= 1.0 + kGrowthTolerance;
  if (!out.stable) return out;
  const int max_steps = static_cast<int>(std::floor(max_extra_delay / dt + 1e-9));
  for (int n = 1; n <= max_steps; ++n) {
    if (radius(n * dt) > 1.0 + kGrowthTolerance) {
      double lo = (n - 1) * dt, hi = n * dt;
      for (int i = 0; i < 30; ++i) {
        const double mid = 0.5 * (lo + hi);
        (radius(mid) > 1.0 + kGrowthTolerance ? hi : lo) = mid;
      }
      out.margin = 0.5 * (lo + hi);
      break;
    }
  }
  return out;
}

LoopContinuousStability continuous_loop_crossings(double period, double zeta, double alpha,
                                                  double dt, const LinearDynamics& loop,
                                                  int branches) {
  require_loop_inputs(dt, loop);
  const SdofParameters p = sdof_parameters(period, zeta, alpha);
  const auto q = [&](double w) {
    return std::complex<double>(p.k_numerical - p.m * w * w, p.c * w);
  };
  const auto f = [&](double w) {
    return std::abs(q(w)) - p.k_experimental * std::abs(loop.frequency_response(w));
  };
  LoopContinuousStability out;
  if (p.k_experimental > 0.0) {
    const double w_min = 1e-3 * std::sqrt((p.k_numerical + p.k_experimental) / p.m);
    const double w_max = std::numbers::pi / dt;
    constexpr int kGrid = 20000;
    double w_prev = w_min, f_prev = f(w_min);
    for (int i = 1; i <= kGrid; ++i) {
      const double w = w_min * std::pow(w_max / w_min, static_cast<double>(i) / kGrid);
      const double fw = f(w);
      if ((f_prev < 0) != (fw < 0)) {
        const double root = bisect_sign_change(f, w_prev, w, f_prev);
        const std::complex<double> z =
            -q(root) / (p.k_experimental * loop.frequency_response(root));
        double phase = std::fmod(-std::arg(z), 2.0 * std::numbers::pi);
        if (phase < 0) phase += 2.0 * std::numbers::pi;
        for (int j = 0; j < branches; ++j)
          out.crossings.push_back({root, (phase + 2.0 * std::numbers::pi * j) / root, j});
      }
      w_prev = w;
      f_prev = fw;
    }
  }
  std::sort(out.crossings.begin(), out.crossings.end(),
            [](const DelayCrossing& l, const DelayCrossing& r) { return l.delay < r.delay; });
  if (!out.crossings.empty()) out.margin = out.crossings.front().delay;
  return out;
}

CompensatedStability compensated_stability(IntegratorKind kind, double period, double zeta,
                                           double alpha, double dt, const DelayChain& loop,
                                           double max_extra_delay, int branches) {
  const LoopDiscreteStability discrete =
      discrete_loop_stability(kind, period, zeta, alpha, dt, loop, max_extra_delay);
  LoopContinuousStability continuous =
      continuous_loop_crossings(period, zeta, alpha, dt, loop, branches);
  CompensatedStability out;
  out.stable = discrete.stable;
  out.spectral_radius = discrete.spectral_radius;
  out.discrete_margin = discrete.margin;
  out.max_extra_delay = max_extra_delay;
  out.continuous_margin = continuous.margin;
  out.crossings = std::move(continuous.crossings);
  if (const Compensator* compensator = loop.compensator()) {
    const Linearity adapting = compensator->linearity();
    if (adapting.kind == Linearity::Kind::kFrozen) out.frozen_coefficients = adapting.note;
  }
  if (const Linearity l = loop.linearity(); l.kind == Linearity::Kind::kLinearised)
    out.linearised = l.note;
  return out;
}

double simulated_growth(IntegratorKind kind, double period, double zeta, double alpha, double dt,
                        DelayChain loop, double duration) {
  HybridSetup setup;
  setup.model = make_sdof(period, zeta);
  setup.dt = dt;
  setup.integrator = kind;
  setup.partition = partition_by_fraction(setup.model.storey_stiffness, alpha, linear_factory());
  setup.delays.push_back(std::move(loop));
  GroundMotion pulse{"pulse", dt,
                     std::vector<double>(static_cast<std::size_t>(duration / dt), 0.0)};
  pulse.acceleration[1] = 100.0;
  SimulationOptions options;
  options.divergence_bound = 1e12;
  const SimulationResult r = simulate(setup, pulse, options);
  const auto n = r.displacement.rows();
  const double early = r.displacement.topRows(n / 3).cwiseAbs().maxCoeff();
  const double late = r.displacement.bottomRows(n / 3).cwiseAbs().maxCoeff();
  return late / early;
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
  const auto limit = critical();
  const std::string discrete_text =
      !discrete_skipped.empty()
          ? "discrete check skipped: " + discrete_skipped
          : "discrete none up to " + std::to_string(discrete_searched_steps) + " steps";
  const std::string continuous_text = coupled ? "continuous (coupled)" : "continuous";
  if (!limit) {
    return "lag " + format_ms(lag) + ": stable for every delay (" + continuous_text + "; " +
           discrete_text + ")";
  }
  const double m = margin();
  return "lag " + format_ms(lag) + " against a critical delay of " + format_ms(*limit) + " (" +
         continuous_text + " " + (continuous ? format_ms(*continuous) : "none") + ", " +
         (discrete ? "discrete " + format_ms(*discrete) : discrete_text) + "; mode " +
         std::to_string(governing_mode) + ", T = " + format_number(governing_period, 3) +
         " s, experimental fraction " + format_number(governing_fraction, 3) + "): " +
         (m < 0 ? "PAST it by " + format_number(-m * 100.0, 3) + " %"
                : format_number(m * 100.0, 3) + " % below it");
}

void CriticalDelayCheck::govern_by_mode_nearest(double omega, const Modes& modes,
                                                const SparseMat& k_experimental) {
  Eigen::Index nearest = 0;
  (modes.omega.array() - omega).abs().minCoeff(&nearest);
  const double omega_i = modes.omega[nearest];
  const Vec phi = modes.shapes.col(nearest);
  governing_mode = static_cast<int>(nearest) + 1;
  governing_period = 2.0 * std::numbers::pi / omega_i;
  governing_fraction = std::clamp(phi.dot(k_experimental * phi) / (omega_i * omega_i), 0.0, 1.0);
}

namespace {

// What the modal check assumes for a model of `dofs` DOFs checked on its lowest `count` modes.
std::string modal_assumption(int dofs, int count) {
  std::string text = dofs == 1
                         ? "exact for one DOF (the experimental part at its initial stiffness)"
                         : "modal approximation over the " + std::to_string(dofs) +
                               " modes of (M, K), each an SDOF with its modal damping and "
                               "experimental fraction phi' K_e phi / omega^2; the coupling the "
                               "delayed force adds between modes is ignored; the experimental "
                               "part at its initial stiffness";
  if (count < dofs)
    text += "; the lowest " + std::to_string(count) +
            " modes only (the model is held sparse: a sparse eigensolver gives them; the higher "
            "modes are not checked)";
  return text;
}

// Where the modes do not decouple K_e and C, the coupled analysis gives the continuous limit;
// the governing mode is the one nearest the crossing's frequency.
void apply_coupled(CriticalDelayCheck& check, const StructuralModel& model,
                   const SparseMat& k_experimental, const Modes& modes) {
  const CoupledStability coupled = coupled_critical_delay(model, k_experimental, modes);
  check.coupled = true;
  check.modal_continuous = check.continuous;
  check.continuous = coupled.critical_delay;
  check.assumed = coupled.assumed +
                  "; the discrete limit by the modal approximation (each mode an SDOF with its "
                  "modal damping and experimental fraction)";
  if (coupled.critical_delay) check.govern_by_mode_nearest(coupled.omega, modes, k_experimental);
}

}  // namespace

bool discrete_analysis_covers(IntegratorKind kind) {
  return kind != IntegratorKind::kAlphaOS && kind != IntegratorKind::kKRAlpha;
}

CriticalDelayCheck check_critical_delay(const StructuralModel& model,
                                        const std::vector<double>& experimental_storey_stiffness,
                                        IntegratorKind kind, double dt, double lag) {
  const int dofs = model.dofs();
  if (static_cast<int>(experimental_storey_stiffness.size()) != dofs) {
    throw std::invalid_argument(
        "critical delay check: one experimental stiffness per storey expected");
  }
  // K_e of a shear building from the storeys' experimental stiffnesses.
  Mat k_experimental;
  StoreyAssembly(dofs).tangent(Eigen::Map<const Vec>(experimental_storey_stiffness.data(), dofs),
                               k_experimental);
  return check_modal_critical_delay(model, k_experimental, kind, dt, lag);
}

CriticalDelayCheck check_modal_critical_delay(const StructuralModel& model,
                                              const SparseMat& k_experimental, IntegratorKind kind,
                                              double dt, double lag) {
  if (!(dt > 0)) throw std::invalid_argument("critical delay check: dt must be > 0 s");
  const int dofs = model.dofs();
  if (k_experimental.rows() != dofs || k_experimental.cols() != dofs)
    throw std::invalid_argument(
        "critical delay check: K_e must be n x n for the structure's n DOFs");
  // A model held sparse: its lowest modes only, from the sparse eigensolver (no n x n problem).
  constexpr int kSparseModes = 20;
  const int count = model.is_sparse() ? std::min(kSparseModes, dofs - 1) : dofs;
  const Modes modes = lowest_modes(model, count);
  CriticalDelayCheck check;
  check.lag = lag;
  const int lag_steps = lag > 0 ? static_cast<int>(std::ceil(lag / dt - 1e-9)) : 0;
  check.discrete_searched_steps = std::min(lag_steps + 1, CriticalDelayCheck::kMaxDiscreteSteps);
  check.assumed = modal_assumption(dofs, count);
  if (!discrete_analysis_covers(kind))
    check.discrete_skipped = "the discrete delay analysis does not cover " + to_string(kind);
  for (int i = 0; i < count; ++i) {
    const double omega = modes.omega[i];
    const Vec phi = modes.shapes.col(i);
    const double zeta = damping_quadratic(model, phi) / (2.0 * omega);
    const double alpha = std::clamp(phi.dot(k_experimental * phi) / (omega * omega), 0.0, 1.0);
    const double period = 2.0 * std::numbers::pi / omega;
    const ContinuousStability continuous = continuous_critical_delay(period, zeta, alpha);
    if (continuous.critical_delay &&
        (!check.continuous || *continuous.critical_delay < *check.continuous)) {
      check.continuous = continuous.critical_delay;
      check.governing_mode = i + 1;
      check.governing_period = period;
      check.governing_fraction = alpha;
    }
    if (i == 0 && !check.continuous) {
      check.governing_period = period;
      check.governing_fraction = alpha;
    }
    if (!check.discrete_skipped.empty()) continue;
    // Searched past the lag to 1.5x the mode's continuous limit, so the discrete limit is found
    // (and reported) also for a lag below it.
    const double reach = continuous.critical_delay ? 1.5 * *continuous.critical_delay / dt : 0.0;
    const int steps = std::min(CriticalDelayCheck::kMaxDiscreteSteps,
                               std::max(lag_steps + 1, static_cast<int>(std::ceil(reach))));
    check.discrete_searched_steps = std::max(check.discrete_searched_steps, steps);
    const DiscreteStability discrete =
        discrete_critical_delay(kind, period, zeta, alpha, dt, steps);
    if (discrete.first_unstable_delay &&
        (!check.discrete || *discrete.first_unstable_delay < *check.discrete)) {
      check.discrete = discrete.first_unstable_delay;
    }
  }
  if (dofs > 1 && !modes_decouple(model, k_experimental, modes))
    apply_coupled(check, model, k_experimental, modes);
  return check;
}

}  // namespace rths::core
