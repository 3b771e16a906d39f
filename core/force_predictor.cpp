#include "core/force_predictor.h"

#include "core/number_text.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rths::core {

namespace {

void require(bool ok, const std::string& label, const std::string& what) {
  if (!ok) throw std::invalid_argument(label + ": " + what);
}

}  // namespace

namespace {
constexpr int kK = 0, kC = 1, kH = 2, kT = 3, kF0 = 4;  // theta's order
constexpr double kLagExplains = 0.005;                  // the T hold's 0.5 % (header)
constexpr double kLagTrusted = 0.05;                    // and its 5 % residual (header)
constexpr int kHoldDigits = 3;  // significant digits of the figures a HOLD's reason prints
}  // namespace

ForcePredictor::ForcePredictor(const PredictorParameters& parameters, double dt,
                               const std::string& label, const RestoringForceModel* shape)
    : p_(parameters), dt_(dt) {
  require(dt > 0 && std::isfinite(dt), label, "dt must be > 0 s");
  require(std::isfinite(p_.stiffness) && p_.stiffness > 0, label,
          "stiffness must be > 0 N/m (the declared specimen's)");
  require(std::isfinite(p_.damping) && p_.damping >= 0, label, "damping must be >= 0 N s/m");
  require(std::isfinite(p_.forgetting_time) && p_.forgetting_time > 0, label,
          "forgetting_time must be > 0 s");
  require(std::isfinite(p_.min_displacement) && p_.min_displacement >= 0, label,
          "min_displacement must be >= 0 m");
  require(std::isfinite(p_.error_window) && p_.error_window >= dt, label,
          "error_window must be at least one step (" + std::to_string(dt) + " s)");
  require(std::isfinite(p_.max_relative_error) && p_.max_relative_error >= 0, label,
          "max_relative_error must be >= 0 (0: no bound)");
  require(std::isfinite(p_.force_lag) && p_.force_lag >= 0, label, "force_lag must be >= 0 s");
  initial_[kK] = p_.stiffness;
  initial_[kT] = p_.force_lag;
  adopt_shape(shape, label);
  if (p_.damping > 0) initial_[kC] = p_.damping;
  lambda_ = std::exp(-dt / p_.forgetting_time);
  const auto window = static_cast<std::size_t>(std::llround(p_.error_window / dt));
  error_sq_.assign(std::max<std::size_t>(window, 1), 0.0);
  force_sq_.assign(error_sq_.size(), 0.0);
  reset();
}

// A dashpot and a mass declared with the specimen are not its shape (header: why); a hysteretic
// shape gives the z column and splits k0 into k and h.
void ForcePredictor::adopt_shape(const RestoringForceModel* declared, const std::string& label) {
  const auto* inertial = dynamic_cast<const InertialSpecimen*>(declared);
  const RestoringForceModel* restoring = inertial ? &inertial->restoring() : declared;
  if (p_.shape) restoring = p_.shape.get();
  if (!restoring) return;
  const double k_r = restoring->initial_stiffness();
  require(std::isfinite(k_r) && k_r > 0, label,
          "the specimen's model (" + restoring->describe() + ") has no positive initial stiffness");
  if (inertial) {
    initial_[kC] = inertial->damping() * p_.stiffness / inertial->initial_stiffness();
    declared_mass_ = inertial->mass();
  }
  if (!p_.specimen_shape) return;
  if (const auto* hysteretic = dynamic_cast<const HystereticModel*>(restoring)) {
    HystereticModel::Parts parts = hysteretic->parts();
    present_[kH] = true;
    initial_[kK] = parts.linear_ratio * p_.stiffness;
    initial_[kH] = (1.0 - parts.linear_ratio) * p_.stiffness * parts.yield_drift;
    command_z_ = parts.unit_hysteresis->clone();
    measured_z_ = std::move(parts.unit_hysteresis);
    return;
  }
  shape_stiffness_ = k_r;
  command_shape_ = restoring->clone();
  measured_shape_ = restoring->clone();
}

ForcePredictor::ForcePredictor(const ForcePredictor& other)
    : p_(other.p_),
      dt_(other.dt_),
      lambda_(other.lambda_),
      declared_mass_(other.declared_mass_),
      free_damping_(other.free_damping_),
      fit_residual_(other.fit_residual_),
      refused_stiffness_(other.refused_stiffness_),
      lag_fitted_(other.lag_fitted_),
      f_sq_(other.f_sq_),
      last_answer_(other.last_answer_),
      last_drift_(other.last_drift_),
      last_f_(other.last_f_),
      error_(other.error_),
      updates_(other.updates_),
      error_sq_(other.error_sq_),
      force_sq_(other.force_sq_),
      head_(other.head_),
      filled_(other.filled_),
      sum_error_sq_(other.sum_error_sq_),
      sum_force_sq_(other.sum_force_sq_),
      command_shape_(other.command_shape_ ? other.command_shape_->clone() : nullptr),
      measured_shape_(other.measured_shape_ ? other.measured_shape_->clone() : nullptr),
      command_z_(other.command_z_ ? other.command_z_->clone() : nullptr),
      measured_z_(other.measured_z_ ? other.measured_z_->clone() : nullptr),
      shape_stiffness_(other.shape_stiffness_) {
  for (int i = 0; i < kTerms; ++i) {
    theta_[i] = other.theta_[i];
    initial_[i] = other.initial_[i];
    standard_error_[i] = other.standard_error_[i];
    present_[i] = other.present_[i];
    last_phi_[i] = other.last_phi_[i];
    b_[i] = other.b_[i];
    for (int j = 0; j < kTerms; ++j) s_[i][j] = other.s_[i][j];
  }
}

double ForcePredictor::command_basis(double x) {
  return command_shape_ ? command_shape_->step(x) / shape_stiffness_ : x;
}

double ForcePredictor::measured_basis(double x) {
  return measured_shape_ ? measured_shape_->step(x) / shape_stiffness_ : x;
}

double ForcePredictor::command_hysteresis(double x) {
  return command_z_ ? command_z_->step(x) : 0.0;
}

double ForcePredictor::measured_hysteresis(double x) {
  return measured_z_ ? measured_z_->step(x) : 0.0;
}

PredictorTerms ForcePredictor::terms(const double theta[kTerms]) {
  return {theta[kK], theta[kC], theta[kH], theta[kT], theta[kF0]};
}

void ForcePredictor::reset() {
  for (auto* shape :
       {command_shape_.get(), measured_shape_.get(), command_z_.get(), measured_z_.get()})
    if (shape) shape->reset();
  for (int i = 0; i < kTerms; ++i) {
    theta_[i] = initial_[i];
    standard_error_[i] = std::nan("");
    last_phi_[i] = b_[i] = 0.0;
    for (int j = 0; j < kTerms; ++j) s_[i][j] = 0.0;
  }
  free_damping_ = fit_residual_ = f_sq_ = 0.0;
  refused_stiffness_ = lag_fitted_ = false;
  last_answer_ = -1;
  last_drift_ = last_f_ = error_ = 0.0;
  updates_ = 0;
  std::fill(error_sq_.begin(), error_sq_.end(), 0.0);
  std::fill(force_sq_.begin(), force_sq_.end(), 0.0);
  head_ = filled_ = 0;
  sum_error_sq_ = sum_force_sq_ = 0.0;
}

double ForcePredictor::residual(const double theta[kTerms]) const {
  double r = f_sq_;
  for (int i = 0; i < kTerms; ++i) {
    r -= 2.0 * theta[i] * b_[i];
    for (int j = 0; j < kTerms; ++j) r += theta[i] * s_[i][j] * theta[j];
  }
  return r;
}

// From the column-scaled normal equations (unit-free, so one conditioning bound serves every
// specimen): refused when the scaled free block's smallest eigenvalue is below 1e-3 (two
// columns: |correlation| above 0.999).
bool ForcePredictor::solve(const bool free[kTerms], double theta[kTerms], double* error) const {
  using Matrix = Eigen::Matrix<double, kTerms, kTerms>;
  using Vector = Eigen::Matrix<double, kTerms, 1>;
  Matrix a = Matrix::Identity();
  Vector rhs = Vector::Zero(), scale = Vector::Ones();
  int count = 0;
  for (int i = 0; i < kTerms; ++i) {
    if (!free[i]) continue;
    if (!(s_[i][i] > 0)) return false;
    scale[i] = 1.0 / std::sqrt(s_[i][i]);
    ++count;
  }
  for (int i = 0; i < kTerms; ++i) {
    if (!free[i]) continue;
    double b = b_[i];
    for (int j = 0; j < kTerms; ++j)
      if (!free[j]) b -= s_[i][j] * theta[j];
    rhs[i] = scale[i] * b;
    for (int j = 0; j < kTerms; ++j)
      if (free[j]) a(i, j) = scale[i] * s_[i][j] * scale[j];
  }
  const Eigen::SelfAdjointEigenSolver<Matrix> eigen(a, Eigen::EigenvaluesOnly);
  if (!(eigen.eigenvalues().minCoeff() > 1e-3)) return false;
  const Eigen::LDLT<Matrix> factor(a);
  const Vector y = factor.solve(rhs);
  double out[kTerms];
  for (int i = 0; i < kTerms; ++i) {
    out[i] = free[i] ? scale[i] * y[i] : theta[i];
    if (!std::isfinite(out[i])) return false;
  }
  std::copy(out, out + kTerms, theta);
  if (!error) return true;
  const double weight = s_[kF0][kF0];
  const double variance = std::max(residual(theta), 0.0) / std::max(weight - count, 1.0);
  const Matrix inverse = factor.solve(Matrix::Identity());
  for (int i = 0; i < kTerms; ++i)
    error[i] =
        free[i] ? scale[i] * std::sqrt(variance * std::max(inverse(i, i), 0.0)) : std::nan("");
  return true;
}

// The holds of the header, in its order, T held at its declared value unless `lag`; false when
// no set of free terms is well conditioned. `c_free`: the first round's c.
bool ForcePredictor::constrained_fit(double theta[kTerms], bool free[kTerms], bool lag,
                                     double& c_free) const {
  bool negative_held[kTerms] = {};
  for (int round = 0; round < kTerms; ++round) {
    for (int i = 0; i < kTerms; ++i) {
      free[i] = present_[i] && !negative_held[i] && (lag || i != kT);
      theta[i] = negative_held[i] ? 0.0 : (i == kT && !lag ? initial_[kT] : theta_[i]);
    }
    bool ok = solve(free, theta, nullptr);
    for (int weak : {kT, kH}) {
      if (ok || !free[weak]) continue;
      free[weak] = false;
      ok = solve(free, theta, nullptr);
    }
    if (!ok) return false;
    if (round == 0) c_free = free[kC] ? theta[kC] : 0.0;
    // k may be 0 beside a hysteresis (an MR damper has no spring); alone it must be > 0.
    int negative = -1;
    for (int i : {kC, kT, kH, kK})
      if (negative < 0 && free[i] && theta[i] < 0 && (i != kK || present_[kH])) negative = i;
    if (negative < 0) return true;
    negative_held[negative] = true;
  }
  return false;
}

// The constrained fit with the lag term free, kept only where it earns its place (header).
bool ForcePredictor::fit(double theta[kTerms], bool free[kTerms]) {
  double c_free = 0.0, without[kTerms], c_without = 0.0;
  bool without_free[kTerms];
  if (!constrained_fit(theta, free, true, c_free)) return false;
  free_damping_ = c_free;
  if (!free[kT] || !constrained_fit(without, without_free, false, c_without)) return true;
  const double scale = std::max(f_sq_, 1e-300);
  const double explained = (residual(without) - residual(theta)) / scale;
  if (explained >= kLagExplains * kLagExplains &&
      residual(theta) <= kLagTrusted * kLagTrusted * scale)
    return true;
  std::copy(without, without + kTerms, theta);
  std::copy(without_free, without_free + kTerms, free);
  free_damping_ = c_without;
  return true;
}

void ForcePredictor::learn(const double phi[kTerms], double f, long steps_since) {
  const double decay = std::pow(lambda_, static_cast<double>(steps_since));
  for (int i = 0; i < kTerms; ++i) {
    for (int j = 0; j < kTerms; ++j) s_[i][j] = decay * s_[i][j] + phi[i] * phi[j];
    b_[i] = decay * b_[i] + phi[i] * f;
  }
  f_sq_ = decay * f_sq_ + f * f;
  if (!p_.adapt) return;
  // s_[kF0][kF0] is the forgetting's weight of the samples (their count, decayed).
  if (!(s_[kK][kK] > 0 && s_[kC][kC] > 0)) return;
  if (std::sqrt(s_[kK][kK] / s_[kF0][kF0]) < p_.min_displacement) return;
  double theta[kTerms];
  bool free[kTerms];
  if (!fit(theta, free)) return;
  refused_stiffness_ = !(theta[kK] > 0 || (present_[kH] && theta[kK] >= 0 && theta[kH] > 0));
  if (refused_stiffness_) return;
  solve(free, theta, standard_error_);
  std::copy(theta, theta + kTerms, theta_);
  lag_fitted_ = free[kT];
  fit_residual_ = f_sq_ > 0 ? std::sqrt(std::max(residual(theta_), 0.0) / f_sq_) : 0.0;
  ++updates_;
}

double ForcePredictor::windowed_error() const {
  if (filled_ < error_sq_.size() || !(sum_force_sq_ > 0)) return 0.0;
  return std::sqrt(std::max(sum_error_sq_, 0.0) / sum_force_sq_);
}

double ForcePredictor::motion_rate() const {
  return s_[kK][kK] > 0 ? std::sqrt(s_[kC][kC] / s_[kK][kK]) : 0.0;
}

std::string ForcePredictor::model_text() const {
  std::ostringstream text;
  const auto term = [&](const char* name, double value, double error, double unit_scale,
                        const char* unit) {
    if (text.tellp() > 0) text << ", ";
    text << name << " " << format_number(unit_scale * value, kHoldDigits) << " +/- "
         << (std::isfinite(error) ? format_number(unit_scale * error, kHoldDigits)
                                  : std::string("held"))
         << " " << unit;
  };
  term("k", theta_[kK], standard_error_[kK], 1.0, "N/m");
  term("c", theta_[kC], standard_error_[kC], 1.0, "N s/m");
  if (present_[kH]) term("h", theta_[kH], standard_error_[kH], 1.0, "N");
  term("T", theta_[kT], standard_error_[kT], 1e3, "ms");
  term("f0", theta_[kF0], standard_error_[kF0], 1.0, "N");
  return text.str();
}

std::string ForcePredictor::rejection() const {
  std::ostringstream text;
  const auto add = [&text](const std::string& line) {
    if (text.tellp() > 0) text << "; ";
    text << line;
  };
  const double k = theta_[kK], lag = theta_[kT], rate = motion_rate();
  if (refused_stiffness_)
    add("the force does not rise with the drift (a fit with k <= 0 was refused): the specimen "
        "lost its stiffness, or the force or drift channel has the wrong sign");
  const bool lags = free_damping_ < 0 && k > 0;  // the best c wanted negative: a lag left over
  if (lags && !lag_fitted_)
    add("the measured force lags the measured drift by at least " +
        format_number(1e3 * -free_damping_ / k, kHoldDigits) + " ms (-c / k of the best fit, c " +
        format_number(free_damping_, kHoldDigits) +
        " N s/m, held at 0; a dashpot lengthens it): the model lacks the force channel's lag (a "
        "load cell or filter): its first-order lag term was held, the answers telling it from "
        "the dashpot too little or leaving more than 5 % with it");
  if (lags && lag_fitted_)
    add("the measured force lags the measured drift by more than the model's first-order lag "
        "term follows (T " +
        format_number(1e3 * lag, kHoldDigits) + " ms fitted, and still the best c is " +
        format_number(free_damping_, kHoldDigits) + " N s/m, held at 0: at least " +
        format_number(1e3 * (lag - free_damping_ / k), kHoldDigits) +
        " ms in all): the model lacks the force channel's lag (a load cell or filter)");
  const double bound = p_.max_relative_error;
  if (bound > 0 && fit_residual_ > 0.5 * bound) {
    std::string missing;
    if (lags || (lag_fitted_ && lag * rate > 0.3))
      missing = "the force's lag: T " + format_number(1e3 * lag, kHoldDigits) + " ms is " +
                format_number(lag * rate, kHoldDigits) + " rad at the motion's RMS rate (" +
                format_number(rate, kHoldDigits) +
                " rad/s), or more, past what a first-order lag term follows (shorten the "
                "load cell's filter)";
    else if (!present_[kH])
      missing =
          "hysteresis: declare the specimen's model or force_predictor.model (a Bouc-Wen rths "
          "identify fits)";
    else
      missing =
          "a shape the declared hysteresis does not have (its yield drift or sharpness), or a "
          "rate term other than the dashpot";
    add("the model's own best fit leaves " + format_number(100.0 * fit_residual_, kHoldDigits) +
        " % of the force unexplained: its form (k x + c v" +
        std::string(present_[kH] ? " + h z" : "") + " + f0, lag T) lacks " + missing);
  } else if (bound > 0 && updates_ > 0 && windowed_error() > bound) {
    add("the model's own best fit leaves " + format_number(100.0 * fit_residual_, kHoldDigits) +
        " %: the specimen changes faster than the forgetting time (" +
        format_number(p_.forgetting_time, kHoldDigits) + " s) follows");
  }
  if (declared_mass_ > 0)
    add("the declared specimen mass (" + format_number(declared_mass_, kHoldDigits) +
        " kg) is not in the model");
  return text.str();
}

PredictorOutput ForcePredictor::step(const PredictorInput& in) {
  if (in.answer_step >= 0 && in.answer_step > last_answer_) {
    const bool first = last_answer_ < 0;
    const long since = first ? 1 : in.answer_step - last_answer_;
    const double span = static_cast<double>(since) * dt_;
    const double x = in.measured_displacement, f = in.measured_force;
    const double phi[kTerms] = {measured_basis(x), first ? 0.0 : (x - last_drift_) / span,
                                measured_hysteresis(x), first ? 0.0 : -(f - last_f_) / span, 1.0};
    learn(phi, f, since);
    last_answer_ = in.answer_step;
    std::copy(phi, phi + kTerms, last_phi_);
    last_drift_ = x;
    last_f_ = f;
  }
  PredictorOutput out;
  if (last_answer_ >= 0) {
    double model = 0.0;
    for (int i = 0; i < kTerms; ++i) model += theta_[i] * last_phi_[i];
    error_ = last_f_ - model;
    // One window entry a step; the ring's sums are recomputed on every wrap so that rounding in
    // the running difference cannot accumulate.
    const double e2 = error_ * error_, f2 = last_f_ * last_f_;
    sum_error_sq_ += e2 - error_sq_[head_];
    sum_force_sq_ += f2 - force_sq_[head_];
    error_sq_[head_] = e2;
    force_sq_[head_] = f2;
    head_ = (head_ + 1) % error_sq_.size();
    filled_ = std::min(filled_ + 1, error_sq_.size());
    if (head_ == 0) {
      sum_error_sq_ = sum_force_sq_ = 0.0;
      for (std::size_t i = 0; i < error_sq_.size(); ++i) {
        sum_error_sq_ += error_sq_[i];
        sum_force_sq_ += force_sq_[i];
      }
    }
    out.relative_error = windowed_error();
  }
  out.predicted = theta_[kK] * command_basis(in.command) + theta_[kC] * in.command_velocity +
                  theta_[kH] * command_hysteresis(in.command) + theta_[kF0];
  out.error = last_answer_ >= 0 ? error_ : 0.0;
  out.force = out.predicted + out.error;
  out.exceeded = p_.max_relative_error > 0 && out.relative_error > p_.max_relative_error;
  out.stiffness = theta_[kK];
  out.damping = theta_[kC];
  out.offset = theta_[kF0];
  out.hysteretic = theta_[kH];
  out.force_lag = theta_[kT];
  return out;
}

std::string ForcePredictor::describe() const {
  std::ostringstream text;
  text << "Smith predictor (k0 " << p_.stiffness << " N/m, c0 " << p_.damping << " N s/m"
       << (present_[kH] ? ", hysteresis h0 " + format_number(initial_[kH], kHoldDigits) + " N" : "")
       << ", force lag " << 1e3 * p_.force_lag << " ms"
       << (p_.adapt ? ", fitted online, forgetting " + std::to_string(p_.forgetting_time) + " s"
                    : ", fixed")
       << ")";
  return text.str();
}

PredictorSet::PredictorSet(const std::vector<std::optional<PredictorParameters>>& parameters,
                           double dt, const std::vector<const RestoringForceModel*>& specimens) {
  bool any = false;
  for (const auto& p : parameters) any = any || p.has_value();
  if (!any) return;
  blocks_.resize(parameters.size());
  last_.resize(parameters.size());
  for (std::size_t a = 0; a < parameters.size(); ++a)
    if (parameters[a])
      blocks_[a].emplace(*parameters[a], dt, "force predictor of actuator " + std::to_string(a + 1),
                         a < specimens.size() ? specimens[a] : nullptr);
}

void PredictorSet::reset() {
  for (auto& block : blocks_)
    if (block) block->reset();
  std::fill(last_.begin(), last_.end(), PredictorOutput{});
}

}  // namespace rths::core
