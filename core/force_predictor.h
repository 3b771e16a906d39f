#pragma once
// Network-delay compensation on the force path: a Smith predictor with an online-updated model
// of a remote experimental part (one per actuator of a remote link).
//
// Why this scheme. A remote link delays the force coming back by its round trip; every
// compensator of core/compensation.h shapes the command for the actuator's lag and cannot see
// it. Three families exist in the distributed-RTHS literature:
//   - force prediction by extrapolation (polynomial or ATS on the force history): the lead it
//     must supply grows with the round trip, its gain at high frequency grows as (w T)^order, and
//     at 60 ms on a 2 Hz structure (w T ~ 0.75 rad) it amplifies noise and jitter into the loop;
//   - two-loop schemes (a fast local loop around a local model, a slow loop that re-synchronises
//     the sites): they need a model of the remote part anyway, plus a second integrator state to
//     reconcile, and they change what the coordinator integrates, which would break "lockstep
//     equals in process" unless both run the same two loops;
//   - a Smith predictor (chosen): the integrator uses a local model of the remote part now, and
//     corrects it by what the model got wrong at the step the newest answer describes. The loop's
//     delay then acts on the model's error only (the error term below), never on the whole force.
// The correction compares the measured force with the model evaluated at the displacement the
// remote sensor measured in the same answer, not at a delayed copy of the command: the pair is
// consistent whatever the lag, jitter, drift or loss of the link (no delay estimate is needed),
// and the actuator's own lag leaves the error too, since the model is of the specimen alone. A
// model fitted against the command would learn the actuator's lag as negative damping
// (c ~ -k tau) and feed it back undelayed.
//
// Input (PredictorInput), once per integrator step k, dt apart:
//   u, v        m, m/s: the drift the integrator computed for this step and its velocity;
//   answer_step the step the link's newest answer answers (-1: none has arrived yet);
//   x_m, f_m    m, N: that answer's measured drift and force (ignored while answer_step < 0).
// Output (PredictorOutput): the force (N) the integrator uses, and the diagnostics below.
// The model (what lab specimens do: a spring, a dashpot, a hysteresis, a force channel's lag),
// with theta = [k, c, h, T, f0] (PredictorTerms):
//   g(x, v)   = k x + c v + h z(x) + f0      (N)  the specimen's force at drift x, rate v
//   f_m + T f_m' = g(x_m, v_m)                     the measured force lags it by T (to first order)
//   k N/m, c N s/m, h N (the hysteretic force, rths identify's F_bw), T s, f0 N (an offset: a
//   yielded specimen carries one at zero drift). z is the declared shape's dimensionless
//   hysteretic variable (core::HystereticModel::Parts: Bouc-Wen's z / uy, the bilinear's
//   elastic-perfectly-plastic drift / uy; |z| <= 1), one copy driven by the measured drift at
//   each new answer and one by the command at every step (a hysteretic model keeps its own path,
//   and its shape parameters uy, n, beta stay as declared: only the terms above are fitted).
//   Without a hysteretic shape there is no h. A declared shape that is not hysteretic (any other
//   RestoringForceModel) stands in for x as r(x) / k_r, its initial stiffness k_r; with
//   specimen_shape false, x is the drift itself (an equivalent linear model).
//   on a new answer (answer_step greater than the last one seen), over the span since the last:
//     v_m = (x_m - x_m,prev) / ((answer_step - answer_step_prev) dt), f_m' alike (0 at the first)
//     phi = [x_m, v_m, z_m, -f_m', 1];  S <- lambda^n S + phi phi^T;  b <- lambda^n b + phi f_m
//     (n the steps since the last answer, lambda = exp(-dt / forgetting_time): exponential
//     forgetting in time, so a burst of late answers weighs as the steps they describe; S_55 is
//     the samples' weight N, F the forgetting's sum of f_m^2);
//     when adapting and the RMS drift sqrt(S_11 / N) >= min_displacement, theta is the least
//     squares fit over the free terms, each held term at its value (rhs b_i - S_ij theta_j),
//     accepted when the column-scaled S of the free terms is well conditioned (its smallest
//     eigenvalue > 1e-3). Terms are held, in this order, until it is:
//       T, then h, at their current values when their columns cannot be told from the others
//       (h while the specimen is elastic: z ~ x / uy; T for a spring alone: f_m' ~ k v_m);
//       c, T or h at 0 when the fit wants it negative (a passive specimen dissipates; a lag is
//       not a lead), and k beside a hysteresis (an MR damper has no spring), the conditioning
//       then judged again;
//       T at its declared value (force_lag) when freeing it explains less than 0.5 % of the
//       force's RMS (sqrt(rho_declared^2 - rho^2) < 0.005): a lag term fitted to rounding
//       would trade c for T; and when the fit with it still leaves rho > 5 %: the form is
//       wrong (a hysteresis missing or of another shape), and a lag fitted then stands in for
//       the shape's error (a line on a yielding column fits T ~ 16 ms) and feeds it back.
//     A fit whose force does not rise with the drift (k <= 0, and h <= 0 or absent) is refused
//     (the model keeps its last theta). Recursive least squares
//     with forgetting, information form.
//     Uncertainty (PredictorTerms of standard errors; NaN for a term held or absent):
//       se_i = sqrt(sigma^2 (S_free^-1)_ii), sigma^2 = (F - 2 theta^T b + theta^T S theta) /
//       max(N - p, 1), p the free terms: the white-residual figure, a lower bound when the
//       residual is correlated from step to step (a missing term's is).
//     What the data said of the model (rejection(), named in a HOLD's reason):
//       c_free, the fit's c before the c >= 0 rule: c_free < 0 with T held means the measured
//         force lags the measured drift by at least -c_free / k s, to first order;
//       rho = sqrt(max(0, F - 2 theta^T b + theta^T S theta) / F): the accepted fit's own
//         residual. rho near the relative error: the model's form cannot follow the force (a
//         term is missing: hysteresis, a lag longer than the first-order term follows, T w > 0.3
//         at w = sqrt(S_22 / S_11) the motion's RMS rate over its RMS drift); rho small under a
//         large relative error: the specimen changes faster than forgetting_time.
//     e = f_m + T f_m' - g(x_m, v_m)                               (N, the model's error)
//   every step: f_hat = g(u, v) (z along the command's path);  force = f_hat + e (e = 0 before
//   the first answer): the lag-free force, the force channel's lag removed with the rest.
// A declared specimen with a dashpot or a mass (InertialSpecimen: m x'' + c_s x' + r(x)) gives
// r alone as the shape: its dashpot is the model's c, fitted, and starts at c_s k0 / k_r (the
// declared dashpot scaled as the stiffness is) unless damping > 0 is given; its mass is not in
// the model (its force m a is left to e). Why r alone: the shape's copies are called once per
// new answer (whatever steps it spans) and once per step (whatever the servo period), so a rate
// differenced over their calls is not the specimen's, and a dashpot inside the stiffness basis
// is collinear with the c column: the fit then drives c to 0 and k far off (a damper behind a
// jittered 60 ms link: k 0.36 of the damper's, 70 % error). For the same reason a shape must
// depend on the drift's path alone, never on time or on how often it is called.
//   relative_error: sqrt(sum e^2 / sum f_m^2) over the last error_window of answers (one entry a
//     step: a step without a new answer repeats the last pair), 0 until the window is full or
//     while sum f_m^2 = 0; exceeded when it is above max_relative_error (> 0).
// Initial state: k = alpha k0, h = (1 - alpha) k0 uy (k0 = parameters.stiffness, alpha and uy
// the shape's; without one k = k0, h = 0), c = c0 (above), T = force_lag, f0 = 0; S = b = 0, no
// answer seen.
// Linear dynamics of the compensated loop (core/stability.h predictor_critical_delay): with a
// specimen k_e, c_e realised D late (round trip plus actuator lag), the integrator sees
//   (k u + c v) + (k_e - k) x(t - D) + (c_e - c) v(t - D).
// step() allocates nothing (buffers sized at construction) and is deterministic, so in-process
// and lockstep distributed runs agree bit for bit.

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/restoring_force.h"

namespace rths::core {

struct PredictorParameters {
  double stiffness = 0.0;           // N/m, k0: the declared specimen's initial stiffness, > 0
  double damping = 0.0;             // N s/m, c0 >= 0; 0: the declared dashpot's (above)
  bool adapt = true;                // update theta online; false: a fixed-model Smith predictor
  double forgetting_time = 1.0;     // s, time constant of the forgetting, > 0
  double min_displacement = 1e-4;   // m, RMS drift below which the fit is not trusted, >= 0
  double error_window = 1.0;        // s, window of relative_error, >= dt
  double max_relative_error = 0.0;  // -, bound on relative_error; 0: no bound
  // The declared specimen's shape as the stiffness basis (equations above); false: the drift
  // itself (an equivalent linear model, whatever the specimen).
  bool specimen_shape = true;
  double force_lag = 0.0;  // s, T at the start, >= 0
  // The shape when it is not the declared specimen's (a Bouc-Wen rths identify fitted), with
  // k0 as its initial stiffness; null: the specimen's given to the constructor.
  std::shared_ptr<const RestoringForceModel> shape;
};

// The model's terms (equations above), or their standard errors.
struct PredictorTerms {
  double stiffness = 0.0;   // N/m, k
  double damping = 0.0;     // N s/m, c
  double hysteretic = 0.0;  // N, h
  double force_lag = 0.0;   // s, T
  double offset = 0.0;      // N, f0
};

struct PredictorInput {
  double command = 0.0;                // m, u
  double command_velocity = 0.0;       // m/s, v
  long answer_step = -1;               // step the newest answer answers; -1: none yet
  double measured_displacement = 0.0;  // m, x_m
  double measured_force = 0.0;         // N, f_m
};

struct PredictorOutput {
  double force = 0.0;           // N, f_hat + e: what the integrator uses
  double predicted = 0.0;       // N, f_hat = g(u, v)
  double error = 0.0;           // N, e
  double relative_error = 0.0;  // -, windowed (above)
  bool exceeded = false;        // relative_error > max_relative_error (> 0)
  double stiffness = 0.0;       // N/m, the model's k now
  double damping = 0.0;         // N s/m, the model's c now
  double offset = 0.0;          // N, the model's f0 now
  double hysteretic = 0.0;      // N, the model's h now
  double force_lag = 0.0;       // s, the model's T now
};

class ForcePredictor {
 public:
  static constexpr int kTerms = 5;  // theta = [k, c, h, T, f0]
  // Throws std::invalid_argument opening with `label` and naming the parameter when one is out
  // of its range above, or dt is not > 0.
  // `shape`: the declared specimen's restoring-force model (used when specimen_shape, unless
  // parameters.shape is given; null: the drift itself). Its initial stiffness must be > 0.
  ForcePredictor(const PredictorParameters& parameters, double dt,
                 const std::string& label = "force predictor",
                 const RestoringForceModel* shape = nullptr);
  ForcePredictor(const ForcePredictor& other);
  ForcePredictor& operator=(const ForcePredictor& other) = delete;
  ForcePredictor(ForcePredictor&&) = default;
  PredictorOutput step(const PredictorInput& in);
  void reset();
  const PredictorParameters& parameters() const { return p_; }
  double stiffness() const { return theta_[0]; }
  double damping() const { return theta_[1]; }
  double offset() const { return theta_[4]; }
  bool hysteretic() const { return present_[2]; }  // the model has an h term
  PredictorTerms model() const { return terms(theta_); }
  PredictorTerms uncertainty() const { return terms(standard_error_); }  // NaN: not fitted
  std::size_t updates() const { return updates_; }                       // fits accepted so far
  double free_damping() const { return free_damping_; }  // N s/m, c_free of the last fit
  double fit_residual() const { return fit_residual_; }  // -, rho of the last accepted fit
  // The terms with their standard errors, for a HOLD's reason and the summary:
  // "k 3.05e+05 +/- 210 N/m, c 9.08e+03 +/- 12 N s/m, h 91.3 +/- 0.4 N, T 3.01 +/- 0.02 ms,
  // f0 -2.1 +/- 0.3 N" (a held term's error reads "held").
  std::string model_text() const;
  // What the data say the model lacks (equations above), for a HOLD's reason (the bound passed):
  // a refused k <= 0; c_free < 0 with the lag held, the force's lag it implies; rho above half
  // the bound, the term missing from the model's form (a lag past the first-order term, a
  // hysteresis undeclared or of another shape); else, fitted and past the bound, a specimen
  // changing faster than the forgetting follows; a declared mass the model leaves out. Empty
  // when none applies.
  std::string rejection() const;
  std::string describe() const;

 private:
  static PredictorTerms terms(const double theta[kTerms]);
  void adopt_shape(const RestoringForceModel* declared, const std::string& label);
  void learn(const double phi[kTerms], double f, long steps_since);
  // The least-squares theta over `free` (held terms at `theta`'s values); false when the scaled
  // free block is ill conditioned. `error` gets the standard errors (NaN off `free`) when given.
  bool solve(const bool free[kTerms], double theta[kTerms], double* error) const;
  bool fit(double theta[kTerms], bool free[kTerms]);  // the holds of the equations above
  bool constrained_fit(double theta[kTerms], bool free[kTerms], bool lag, double& c_free) const;
  double residual(const double theta[kTerms]) const;  // F - 2 theta^T b + theta^T S theta
  double windowed_error() const;                      // relative_error (equations above)
  double motion_rate() const;                         // rad/s, w of the equations above
  // The x and z columns along the command's and the measurements' paths.
  double command_basis(double x);
  double measured_basis(double x);
  double command_hysteresis(double x);
  double measured_hysteresis(double x);

  PredictorParameters p_;
  double dt_, lambda_;
  double theta_[kTerms] = {}, initial_[kTerms] = {}, standard_error_[kTerms] = {};
  bool present_[kTerms] = {true, true, false, true, true};
  double declared_mass_ = 0.0;  // kg, the declared specimen's, not in the model
  double free_damping_ = 0.0, fit_residual_ = 0.0;
  bool refused_stiffness_ = false;  // the last fit wanted k <= 0
  bool lag_fitted_ = false;         // T was free in the last accepted fit
  // The forgetting's normal equations over phi: s_ = sum phi phi^T, b_ = sum phi f.
  double s_[kTerms][kTerms] = {}, b_[kTerms] = {}, f_sq_ = 0.0;  // f_sq_: sum f^2, forgotten alike
  long last_answer_ = -1;
  double last_phi_[kTerms] = {};
  double last_drift_ = 0.0, last_f_ = 0.0, error_ = 0.0;
  std::size_t updates_ = 0;
  // Ring of the last error_window steps' e^2 and f_m^2, and their sums.
  std::vector<double> error_sq_, force_sq_;
  std::size_t head_ = 0, filled_ = 0;
  double sum_error_sq_ = 0.0, sum_force_sq_ = 0.0;
  // r(x) / k_r for a shape that is not hysteretic (null: x itself), and z for one that is.
  std::unique_ptr<RestoringForceModel> command_shape_, measured_shape_;
  std::unique_ptr<RestoringForceModel> command_z_, measured_z_;
  double shape_stiffness_ = 1.0;  // k_r, N/m
};

// The predictors of a run's actuators, one or none each, as every evaluator applies them (the
// in-process HybridRestoring and the coordinator's exchange), so both use the same doubles.
// apply(): for each actuator a with a predictor, given its command (m), command rate (m/s), the
// step its newest answer answers (-1: none yet) and that answer's measured drift (m) and force
// (N), writes the force the integrator uses into used[a] and the model's error into error[a]
// (N); without one, used[a] = the measured force and error[a] = 0. Returns the first actuator
// (0-based) whose relative error is past its bound, or -1. No allocation.
class PredictorSet {
 public:
  PredictorSet() = default;
  // @pre each parameter set valid (ForcePredictor's constructor throws otherwise).
  // `specimens`: each actuator's declared specimen model (null where none), for its shape.
  PredictorSet(const std::vector<std::optional<PredictorParameters>>& parameters, double dt,
               const std::vector<const RestoringForceModel*>& specimens = {});
  bool empty() const { return blocks_.empty(); }
  bool has(std::size_t a) const { return a < blocks_.size() && blocks_[a].has_value(); }
  const ForcePredictor& at(std::size_t a) const { return *blocks_[a]; }
  const PredictorOutput& last(std::size_t a) const { return last_[a]; }
  template <class Vector>
  int apply(const Vector& command, const Vector& command_rate, const std::vector<long>& answer,
            const Vector& realised, const Vector& measured, Vector& used, Vector& error) {
    int exceeded = -1;
    for (std::size_t a = 0; a < static_cast<std::size_t>(measured.size()); ++a) {
      const auto i = static_cast<decltype(measured.size())>(a);
      if (!has(a)) {
        used[i] = measured[i];
        error[i] = 0.0;
        continue;
      }
      last_[a] =
          blocks_[a]->step({command[i], command_rate[i], answer[a], realised[i], measured[i]});
      used[i] = last_[a].force;
      error[i] = last_[a].error;
      if (last_[a].exceeded && exceeded < 0) exceeded = static_cast<int>(a);
    }
    return exceeded;
  }
  void reset();

 private:
  std::vector<std::optional<ForcePredictor>> blocks_;
  std::vector<PredictorOutput> last_;
};

}  // namespace rths::core
