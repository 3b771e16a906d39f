#include "core/force_predictor.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace rths::core {

namespace {

void require(bool ok, const std::string& label, const std::string& what) {
  if (!ok) throw std::invalid_argument(label + ": " + what);
}

// Three significant digits, as a HOLD's reason prints its figures.
std::string three(double value) {
  std::ostringstream text;
  text << std::setprecision(3) << value;
  return text.str();
}

}  // namespace

ForcePredictor::ForcePredictor(const PredictorParameters& parameters, double dt,
                               const std::string& label, const RestoringForceModel* shape)
    : p_(parameters), dt_(dt) {
  // A dashpot and a mass declared with the specimen are not its shape (header: why).
  const auto* inertial = dynamic_cast<const InertialSpecimen*>(shape);
  const RestoringForceModel* restoring = inertial ? &inertial->restoring() : shape;
  if (restoring) {
    const double k_r = restoring->initial_stiffness();
    require(std::isfinite(k_r) && k_r > 0, label,
            "the specimen's model (" + shape->describe() + ") has no positive initial stiffness");
    if (inertial) {
      initial_damping_ = inertial->damping() * p_.stiffness / k_r;
      declared_mass_ = inertial->mass();
    }
    if (p_.specimen_shape) {
      shape_stiffness_ = k_r;
      command_shape_ = restoring->clone();
      measured_shape_ = restoring->clone();
    }
  }
  if (p_.damping > 0) initial_damping_ = p_.damping;
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
  lambda_ = std::exp(-dt / p_.forgetting_time);
  const auto window = static_cast<std::size_t>(std::llround(p_.error_window / dt));
  error_sq_.assign(std::max<std::size_t>(window, 1), 0.0);
  force_sq_.assign(error_sq_.size(), 0.0);
  reset();
}

ForcePredictor::ForcePredictor(const ForcePredictor& other)
    : p_(other.p_),
      dt_(other.dt_),
      lambda_(other.lambda_),
      k_(other.k_),
      c_(other.c_),
      offset_(other.offset_),
      initial_damping_(other.initial_damping_),
      declared_mass_(other.declared_mass_),
      free_damping_(other.free_damping_),
      fit_residual_(other.fit_residual_),
      refused_stiffness_(other.refused_stiffness_),
      f_sq_(other.f_sq_),
      last_answer_(other.last_answer_),
      last_x_(other.last_x_),
      last_drift_(other.last_drift_),
      last_v_(other.last_v_),
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
      shape_stiffness_(other.shape_stiffness_) {
  for (int i = 0; i < 3; ++i) {
    b_[i] = other.b_[i];
    for (int j = 0; j < 3; ++j) s_[i][j] = other.s_[i][j];
  }
}

double ForcePredictor::command_basis(double x) {
  return command_shape_ ? command_shape_->step(x) / shape_stiffness_ : x;
}

double ForcePredictor::measured_basis(double x) {
  return measured_shape_ ? measured_shape_->step(x) / shape_stiffness_ : x;
}

void ForcePredictor::reset() {
  if (command_shape_) command_shape_->reset();
  if (measured_shape_) measured_shape_->reset();
  k_ = p_.stiffness;
  c_ = initial_damping_;
  offset_ = 0.0;
  free_damping_ = fit_residual_ = f_sq_ = 0.0;
  refused_stiffness_ = false;
  for (int i = 0; i < 3; ++i) {
    b_[i] = 0.0;
    for (int j = 0; j < 3; ++j) s_[i][j] = 0.0;
  }
  last_answer_ = -1;
  last_x_ = last_drift_ = last_v_ = last_f_ = error_ = 0.0;
  updates_ = 0;
  std::fill(error_sq_.begin(), error_sq_.end(), 0.0);
  std::fill(force_sq_.begin(), force_sq_.end(), 0.0);
  head_ = filled_ = 0;
  sum_error_sq_ = sum_force_sq_ = 0.0;
}

void ForcePredictor::learn(double x, double v, double f, long steps_since) {
  const double decay = std::pow(lambda_, static_cast<double>(steps_since));
  const double phi[3] = {x, v, 1.0};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) s_[i][j] = decay * s_[i][j] + phi[i] * phi[j];
    b_[i] = decay * b_[i] + phi[i] * f;
  }
  f_sq_ = decay * f_sq_ + f * f;
  if (!p_.adapt) return;
  // s_[2][2] is the forgetting's weight of the samples (their count, decayed).
  if (!(s_[0][0] > 0 && s_[1][1] > 0)) return;
  if (std::sqrt(s_[0][0] / s_[2][2]) < p_.min_displacement) return;
  // theta over the columns in `use`, from the column-scaled normal equations (unit-free, so one
  // conditioning bound serves every specimen): refused when the scaled matrix's smallest
  // eigenvalue is below 1e-3 (two columns: |correlation| above 0.999).
  const auto solve = [this](const bool use[3], double theta[3]) {
    Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero(), scale = Eigen::Vector3d::Ones();
    for (int i = 0; i < 3; ++i)
      if (use[i]) scale[i] = 1.0 / std::sqrt(s_[i][i]);
    for (int i = 0; i < 3; ++i) {
      if (!use[i]) continue;
      rhs[i] = scale[i] * b_[i];
      for (int j = 0; j < 3; ++j)
        if (use[j]) a(i, j) = scale[i] * s_[i][j] * scale[j];
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a, Eigen::EigenvaluesOnly);
    if (!(eigen.eigenvalues().minCoeff() > 1e-3)) return false;
    const Eigen::Vector3d y = a.ldlt().solve(rhs);
    for (int i = 0; i < 3; ++i) theta[i] = use[i] ? scale[i] * y[i] : 0.0;
    return std::isfinite(theta[0]) && std::isfinite(theta[1]) && std::isfinite(theta[2]);
  };
  double theta[3];
  const bool all[3] = {true, true, true};
  if (!solve(all, theta)) return;
  free_damping_ = theta[1];
  if (theta[1] < 0) {  // a passive specimen: the best fit with c = 0
    const bool without_damping[3] = {true, false, true};
    if (!solve(without_damping, theta)) return;
  }
  refused_stiffness_ = !(theta[0] > 0);
  if (refused_stiffness_) return;
  k_ = theta[0];
  c_ = theta[1];
  offset_ = theta[2];
  // The least-squares residual over the columns used: F - theta^T b (theta is 0 off them).
  const double explained = theta[0] * b_[0] + theta[1] * b_[1] + theta[2] * b_[2];
  fit_residual_ = f_sq_ > 0 ? std::sqrt(std::max(f_sq_ - explained, 0.0) / f_sq_) : 0.0;
  ++updates_;
}

double ForcePredictor::windowed_error() const {
  if (filled_ < error_sq_.size() || !(sum_force_sq_ > 0)) return 0.0;
  return std::sqrt(std::max(sum_error_sq_, 0.0) / sum_force_sq_);
}

std::string ForcePredictor::rejection() const {
  std::ostringstream text;
  const auto add = [&text](const std::string& line) {
    if (text.tellp() > 0) text << "; ";
    text << line;
  };
  if (refused_stiffness_)
    add("the force does not rise with the drift (a fit with k <= 0 was refused): the specimen "
        "lost its stiffness, or the force or drift channel has the wrong sign");
  if (free_damping_ < 0 && k_ > 0)
    add("the measured force lags the measured drift by at least " +
        three(1e3 * -free_damping_ / k_) + " ms (-c / k of the best fit, c " +
        three(free_damping_) +
        " N s/m, held at 0; a dashpot lengthens it): the model lacks the force channel's lag (a "
        "load cell or filter)");
  const double bound = p_.max_relative_error;
  if (bound > 0 && fit_residual_ > 0.5 * bound)
    add("the model's own best fit leaves " + three(100.0 * fit_residual_) +
        " % of the force unexplained: its form (k x + c v + f0" +
        std::string(command_shape_ ? " on the declared shape" : "") +
        ") lacks a term the specimen has (hysteresis: declare its model; a lag)");
  else if (bound > 0 && updates_ > 0 && windowed_error() > bound)
    add("the model's own best fit leaves " + three(100.0 * fit_residual_) +
        " %: the specimen changes faster than the forgetting time (" + three(p_.forgetting_time) +
        " s) follows");
  if (declared_mass_ > 0)
    add("the declared specimen mass (" + three(declared_mass_) + " kg) is not in the model");
  return text.str();
}

PredictorOutput ForcePredictor::step(const PredictorInput& in) {
  if (in.answer_step >= 0 && in.answer_step > last_answer_) {
    const bool first = last_answer_ < 0;
    const long since = first ? 1 : in.answer_step - last_answer_;
    const double v_m =
        first ? 0.0 : (in.measured_displacement - last_drift_) / (static_cast<double>(since) * dt_);
    const double basis = measured_basis(in.measured_displacement);
    learn(basis, v_m, in.measured_force, since);
    last_answer_ = in.answer_step;
    last_x_ = basis;
    last_drift_ = in.measured_displacement;
    last_v_ = v_m;
    last_f_ = in.measured_force;
  }
  PredictorOutput out;
  if (last_answer_ >= 0) {
    error_ = last_f_ - (k_ * last_x_ + c_ * last_v_ + offset_);
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
  out.predicted = k_ * command_basis(in.command) + c_ * in.command_velocity + offset_;
  out.error = last_answer_ >= 0 ? error_ : 0.0;
  out.force = out.predicted + out.error;
  out.exceeded = p_.max_relative_error > 0 && out.relative_error > p_.max_relative_error;
  out.stiffness = k_;
  out.damping = c_;
  out.offset = offset_;
  return out;
}

std::string ForcePredictor::describe() const {
  std::ostringstream text;
  text << "Smith predictor (k0 " << p_.stiffness << " N/m, c0 " << p_.damping << " N s/m"
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
