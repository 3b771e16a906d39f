#include "core/compensation.h"

#include "core/number_text.h"
#include "core/precondition.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace rths::core {
namespace {

// Second-order backward differences on x[0] (newest), x[1], x[2], x[3].
double backward_velocity(const double* x, double dt) {
  return (3.0 * x[0] - 4.0 * x[1] + x[2]) / (2.0 * dt);
}
double backward_acceleration(const double* x, double dt) {
  return (2.0 * x[0] - 5.0 * x[1] + 4.0 * x[2] - x[3]) / (dt * dt);
}

void require_step(double dt, const std::string& who) {
  require(dt > 0.0 && std::isfinite(dt), who + ": dt must be > 0 s, got " + format_number(dt));
}

// The coefficients' bounds and starting values, which do not depend on dt: the one statement of
// these preconditions, for the block's constructor and for a study config's validation. `label`
// prefixes the message ("adaptive time series compensator", or a config path).

}  // namespace

void require_identity_start(const AtsParameters& p, const std::string& label) {
  const struct {
    const char* name;
    double initial, identity;
    CoefficientBounds bounds;
  } coefficients[] = {{"a0", p.a0, 1.0, p.a0_bounds},
                      {"a1", p.a1, 0.0, p.a1_bounds},
                      {"a2", p.a2, 0.0, p.a2_bounds}};
  for (const auto& c : coefficients) {
    require(c.initial == c.identity, label + ": " + c.name + " must start at " +
                                         format_number(c.identity) + " (the nominal design), got " +
                                         format_number(c.initial));
    require(std::isfinite(c.bounds.min) && std::isfinite(c.bounds.max) &&
                c.bounds.min < c.bounds.max && c.bounds.min <= c.identity &&
                c.identity <= c.bounds.max,
            label + ": " + c.name +
                "_bounds must have min < max and "
                "contain " +
                format_number(c.identity) + " (the nominal design), got [" +
                format_number(c.bounds.min) + ", " + format_number(c.bounds.max) + "]");
  }
}

void check_ats_coefficients(const AtsParameters& p, const std::string& label) {
  const struct {
    const char* name;
    double initial;
    CoefficientBounds bounds;
  } coefficients[] = {
      {"a0", p.a0, p.a0_bounds}, {"a1", p.a1, p.a1_bounds}, {"a2", p.a2, p.a2_bounds}};
  for (const auto& c : coefficients) {
    require(
        std::isfinite(c.bounds.min) && std::isfinite(c.bounds.max) && c.bounds.min < c.bounds.max,
        label + ": " + c.name + "_bounds must have min < max, got [" + format_number(c.bounds.min) +
            ", " + format_number(c.bounds.max) + "]");
    require(c.initial >= c.bounds.min && c.initial <= c.bounds.max,
            label + ": initial_" + c.name + " = " + format_number(c.initial) + " is outside " +
                c.name + "_bounds [" + format_number(c.bounds.min) + ", " +
                format_number(c.bounds.max) + "]");
  }
  require(p.a0_bounds.min > 0.0, label + ": a0_bounds.min must be > 0 (a0 is the command's gain)");
}

std::vector<std::complex<double>> polynomial_roots(const std::vector<double>& coefficients) {
  const std::vector<double> p = trimmed(coefficients);
  const int degree = static_cast<int>(p.size()) - 1;
  if (degree < 1) return {};
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  for (int j = 0; j < degree; ++j) companion(0, j) = -p[static_cast<std::size_t>(j) + 1] / p[0];
  for (int i = 1; i < degree; ++i) companion(i, i - 1) = 1.0;
  Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, false);
  std::vector<std::complex<double>> roots;
  for (int i = 0; i < degree; ++i) roots.push_back(solver.eigenvalues()[i]);
  return roots;
}

// ---------------------------------------------------------------------------------------------

// ---------------------------------------------------------------------------------------------
PolynomialExtrapolation::PolynomialExtrapolation(int order, double lead, int spacing_steps,
                                                 double dt)
    : order_(order), spacing_(spacing_steps), lead_(lead), dt_(dt) {
  require_step(dt, "polynomial compensator");
  require(order >= 1 && order <= 3,
          "polynomial compensator: order must be 1, 2 or 3, got " + std::to_string(order));
  require(lead > 0.0 && lead <= 1.0,
          "polynomial compensator: lead must be in (0, 1] s, got " + format_number(lead));
  require(spacing_steps >= 1, "polynomial compensator: spacing must be at least one step (dt)");
  // Lagrange weights for nodes x_j = -j (in units of the spacing h), evaluated at x = L / h.
  const double x = lead / (spacing_steps * dt);
  for (int j = 0; j <= order; ++j) {
    double c = 1.0;
    for (int m = 0; m <= order; ++m) {
      if (m != j) c *= (x + m) / static_cast<double>(m - j);
    }
    weights_.push_back(c);
  }
  history_.assign(static_cast<std::size_t>(order * spacing_steps + 1), 0.0);
}

double PolynomialExtrapolation::step(const CompensatorInput& in) {
  const std::size_t size = history_.size();
  head_ = (head_ + 1) % size;
  history_[head_] = in.target;
  double command = 0.0;
  for (int j = 0; j <= order_; ++j) {
    const std::size_t back = static_cast<std::size_t>(j * spacing_);
    command += weights_[static_cast<std::size_t>(j)] * history_[(head_ + size - back) % size];
  }
  return command;
}

void PolynomialExtrapolation::reset() {
  std::fill(history_.begin(), history_.end(), 0.0);
  head_ = 0;
}

std::unique_ptr<Compensator> PolynomialExtrapolation::clone() const {
  return std::make_unique<PolynomialExtrapolation>(*this);
}

std::string PolynomialExtrapolation::describe() const {
  return "polynomial(order " + std::to_string(order_) + ", lead " + format_number(lead_ * 1e3) +
         " ms, spacing " + std::to_string(spacing_) + " steps)";
}

std::complex<double> PolynomialExtrapolation::frequency_response(double omega) const {
  const double h = spacing_ * dt_;
  std::complex<double> sum = 0.0;
  for (std::size_t j = 0; j < weights_.size(); ++j)
    sum += weights_[j] * std::exp(std::complex<double>(0.0, -omega * h * static_cast<double>(j)));
  return sum;
}

LinearBlock PolynomialExtrapolation::state_space() const {
  std::vector<double> taps(static_cast<std::size_t>(order_ * spacing_), 0.0);
  for (int j = 1; j <= order_; ++j)
    taps[static_cast<std::size_t>(j * spacing_ - 1)] = weights_[static_cast<std::size_t>(j)];
  return fir_block(weights_[0], taps);
}

// ---------------------------------------------------------------------------------------------
AdaptiveTimeSeries::AdaptiveTimeSeries(const AtsParameters& parameters, double dt,
                                       const std::string& label)
    : p_(parameters), dt_(dt), filter_decay_(0.0) {
  require_step(dt, label);
  require(std::isfinite(p_.window) && p_.window >= 3.0 * dt,
          label + ": window must be >= 3 dt (" + format_number(3.0 * dt) + " s), got " +
              format_number(p_.window));
  require(p_.window / dt <= 1e6,
          label + ": window of " + format_number(p_.window) + " s is more than 1e6 steps");
  check_ats_coefficients(p_, label);
  require(std::isfinite(p_.derivative_cutoff) && p_.derivative_cutoff >= 0.0 &&
              p_.derivative_cutoff < 0.5 / dt,
          label + ": derivative_cutoff must be in [0, Nyquist = " + format_number(0.5 / dt) +
              " Hz), got " + format_number(p_.derivative_cutoff));
  if (p_.derivative_cutoff > 0.0) {
    filter_decay_ = std::exp(-2.0 * std::numbers::pi * p_.derivative_cutoff * dt);
  }
  const auto window = static_cast<std::size_t>(std::llround(p_.window / dt));
  rows_x_.assign(window, 0.0);
  rows_v_.assign(window, 0.0);
  rows_a_.assign(window, 0.0);
  rows_u_.assign(window, 0.0);
  reset();
}

void AdaptiveTimeSeries::reset() {
  a_[0] = p_.a0;
  a_[1] = p_.a1;
  a_[2] = p_.a2;
  std::fill(std::begin(target_), std::end(target_), 0.0);
  std::fill(std::begin(filtered_measured_), std::end(filtered_measured_), 0.0);
  filtered_command_ = last_command_ = 0.0;
  samples_seen_ = updates_ = 0;
  has_previous_ = false;
  row_head_ = row_count_ = 0;
}

std::unique_ptr<Compensator> AdaptiveTimeSeries::clone() const {
  return std::make_unique<AdaptiveTimeSeries>(*this);
}

std::string AdaptiveTimeSeries::describe() const {
  return "ats(window " + format_number(p_.window) + " s, a0 " + format_number(p_.a0) + ", a1 " +
         format_number(p_.a1 * 1e3) + " ms, a2 " + format_number(p_.a2) + " s^2)";
}

Linearity AdaptiveTimeSeries::linearity() const {
  std::ostringstream note;
  note << "time-varying (its coefficients adapt online): analysed with them frozen at their "
       << (updates_ == 0 ? "initial" : "present") << " values a0 = " << a_[0]
       << ", a1 = " << a_[1] * 1e3 << " ms, a2 = " << a_[2] << " s^2";
  return {Linearity::Kind::kFrozen, note.str()};
}

std::complex<double> AdaptiveTimeSeries::frequency_response(double omega) const {
  return {a_[0] - a_[2] * omega * omega, a_[1] * omega};
}

// a0 u + a1 (3u - 4u1 + u2) / 2dt + a2 (2u - 5u1 + 4u2 - u3) / dt^2.
LinearBlock AdaptiveTimeSeries::state_space() const {
  const double v = a_[1] / (2.0 * dt_), q = a_[2] / (dt_ * dt_);
  return fir_block(a_[0] + 3.0 * v + 2.0 * q, {-4.0 * v - 5.0 * q, v + 4.0 * q, -q});
}

// One regression row: the command sent at step k-1 and the measurement it produced.
void AdaptiveTimeSeries::learn(double command, double measured) {
  const double keep = filter_decay_, take = 1.0 - filter_decay_;
  filtered_command_ = keep * filtered_command_ + take * command;
  double* x = filtered_measured_;
  x[3] = x[2];
  x[2] = x[1];
  x[1] = x[0];
  x[0] = keep * x[0] + take * measured;
  ++samples_seen_;
  // The same difference operators as on the target, so the fitted a1, a2 are the ones the
  // command law needs (at rest before the first sample, so no start-up rows are skipped).
  const double velocity = backward_velocity(x, dt_);
  const double acceleration = backward_acceleration(x, dt_);
  row_head_ = (row_head_ + 1) % rows_x_.size();
  rows_x_[row_head_] = x[0];
  rows_v_[row_head_] = velocity;
  rows_a_[row_head_] = acceleration;
  rows_u_[row_head_] = filtered_command_;
  row_count_ = std::min(row_count_ + 1, rows_x_.size());
  if (row_count_ == rows_x_.size()) fit();
}

void AdaptiveTimeSeries::fit() {
  // Normal equations with columns scaled to unit RMS, so x (mm), x' and x'' (m/s^2) weigh alike.
  const std::size_t n = row_count_;
  double scale[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    scale[0] += rows_x_[i] * rows_x_[i];
    scale[1] += rows_v_[i] * rows_v_[i];
    scale[2] += rows_a_[i] * rows_a_[i];
  }
  for (double& s : scale) {
    s = std::sqrt(s / static_cast<double>(n));
    if (!(s > 0.0) || !std::isfinite(s)) return;  // no excitation: keep the coefficients
  }
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d row(rows_x_[i] / scale[0], rows_v_[i] / scale[1], rows_a_[i] / scale[2]);
    normal.noalias() += row * row.transpose();
    rhs.noalias() += row * rows_u_[i];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(normal, Eigen::EigenvaluesOnly);
  const double largest = eigen.eigenvalues().maxCoeff(), smallest = eigen.eigenvalues().minCoeff();
  constexpr double kMinConditionRatio = 1e-10;  // below: the window does not excite all 3 terms
  if (!(smallest > kMinConditionRatio * largest)) return;
  const Eigen::Vector3d solution = normal.ldlt().solve(rhs);
  const CoefficientBounds bounds[3] = {p_.a0_bounds, p_.a1_bounds, p_.a2_bounds};
  for (int i = 0; i < 3; ++i) {
    const double value = solution[i] / scale[i];
    if (!std::isfinite(value)) return;
    a_[i] = std::clamp(value, bounds[i].min, bounds[i].max);
  }
  ++updates_;
}

double AdaptiveTimeSeries::step(const CompensatorInput& in) {
  if (has_previous_) learn(last_command_, in.measured);
  has_previous_ = true;
  double* x = target_;
  x[3] = x[2];
  x[2] = x[1];
  x[1] = x[0];
  x[0] = in.target;
  last_command_ =
      a_[0] * x[0] + a_[1] * backward_velocity(x, dt_) + a_[2] * backward_acceleration(x, dt_);
  return last_command_;
}

// ---------------------------------------------------------------------------------------------
InverseDesign design_inverse(const PlantModel& plant, int lead_order, double rolloff_hz, double dt,
                             const std::string& who) {
  require_step(dt, who);
  require(lead_order >= 1 && lead_order <= 3,
          who + ": lead_order must be 1, 2 or 3, got " + std::to_string(lead_order));
  require(std::isfinite(rolloff_hz) && rolloff_hz > 0.0 && rolloff_hz < 0.25 / dt,
          who + ": rolloff_frequency must be in (0, " + format_number(0.25 / dt) +
              ") Hz (a quarter of the sampling rate), got " + format_number(rolloff_hz));
  require(std::isfinite(plant.delay) && plant.delay >= 0.0,
          who + ": plant delay must be >= 0 s, got " + format_number(plant.delay));
  require(std::isfinite(plant.gain) && plant.gain != 0.0,
          who + ": plant gain must be finite and non-zero");
  const std::vector<double> num = trimmed(plant.numerator), den = trimmed(plant.denominator);
  for (double c : num) require(std::isfinite(c), who + ": plant numerator is not finite");
  for (double c : den) require(std::isfinite(c), who + ": plant denominator is not finite");
  require(num.front() != 0.0, who + ": plant numerator is zero");
  require(den.front() != 0.0, who + ": plant denominator is zero");
  require(num.size() <= den.size(), who + ": plant has more zeros than poles");
  require(num.back() != 0.0 && den.back() != 0.0,
          who + ": plant has a zero or a pole at s = 0 (no finite static gain)");
  for (const auto& zero : polynomial_roots(num)) {
    require(zero.real() < 0.0,
            who + ": plant zero at s = " + format_number(zero.real()) +
                (zero.imag() != 0.0 ? " + " + format_number(zero.imag()) + "i" : "") +
                " is not in the left half-plane: its inverse would be unstable");
  }
  const int relative_degree = static_cast<int>(den.size() - num.size());
  const int filter_order = relative_degree + lead_order;
  const double wf = 2.0 * std::numbers::pi * rolloff_hz;
  InverseDesign design;
  design.lead = plant.delay + filter_order / wf;
  // T_m(sL) = sum x^i / i!, highest power first.
  std::vector<double> taylor(static_cast<std::size_t>(lead_order) + 1);
  double factorial = 1.0, power = 1.0;
  for (int i = 0; i <= lead_order; ++i) {
    if (i > 0) {
      factorial *= i;
      power *= design.lead;
    }
    taylor[static_cast<std::size_t>(lead_order - i)] = power / factorial;
  }
  // Normalised so that D(0) / N(0) and the filter's DC gain are exact.
  std::vector<double> filter{1.0};
  for (int i = 0; i < filter_order; ++i) filter = polynomial_multiply(filter, {1.0 / wf, 1.0});
  design.numerator = polynomial_multiply(den, taylor);
  design.denominator = polynomial_multiply(num, filter);
  for (double& c : design.denominator) c *= plant.gain;
  return design;
}

ModelBasedInverse::ModelBasedInverse(PlantModel plant, int lead_order, double rolloff_hz, double dt,
                                     const std::string& label)
    : ModelBasedInverse(plant, lead_order, rolloff_hz, dt,
                        design_inverse(plant, lead_order, rolloff_hz, dt, label)) {}

ModelBasedInverse::ModelBasedInverse(PlantModel plant, int lead_order, double rolloff_hz, double dt,
                                     const InverseDesign& design)
    : plant_(std::move(plant)),
      lead_order_(lead_order),
      rolloff_hz_(rolloff_hz),
      lead_(design.lead),
      numerator_(design.numerator),
      denominator_(design.denominator),
      filter_(design.numerator, design.denominator, dt, "model-based inverse") {}

double ModelBasedInverse::step(const CompensatorInput& in) {
  return filter_.step({in.time, in.target, 0.0});
}

std::complex<double> ModelBasedInverse::frequency_response(double omega) const {
  const std::complex<double> s(0.0, omega);
  return polynomial_at(numerator_, s) / polynomial_at(denominator_, s);
}

std::optional<PlantModel> ModelBasedInverse::transfer_function() const {
  PlantModel c;
  c.append(numerator_, denominator_);
  return c;
}

std::unique_ptr<Compensator> ModelBasedInverse::clone() const {
  return std::make_unique<ModelBasedInverse>(*this);
}

std::string ModelBasedInverse::describe() const {
  return "model-based inverse(" + plant_.describe() + ", lead " + format_number(lead_ * 1e3) +
         " ms order " + std::to_string(lead_order_) + ", roll-off " + format_number(rolloff_hz_) +
         " Hz)";
}

// ---------------------------------------------------------------------------------------------
AtsParameters adaptive_correction_defaults() {
  AtsParameters p;
  p.window = 1.0;
  p.a0 = 1.0;
  p.a1 = 0.0;
  p.a2 = 0.0;
  p.a0_bounds = {0.5, 2.0};
  p.a1_bounds = {-0.05, 0.05};
  p.a2_bounds = {-1e-3, 1e-3};
  p.derivative_cutoff = 0.0;
  return p;
}

AdaptedModelBasedInverse::AdaptedModelBasedInverse(ModelBasedInverse inverse,
                                                   const AtsParameters& correction, double dt,
                                                   const std::string& label)
    : correction_((require_identity_start(correction, label), correction), dt, label),
      inverse_(std::move(inverse)) {}

double AdaptedModelBasedInverse::step(const CompensatorInput& in) {
  const double corrected = correction_.step(in);
  return inverse_.step({in.time, corrected, in.measured});
}

void AdaptedModelBasedInverse::reset() {
  correction_.reset();
  inverse_.reset();
}

std::complex<double> AdaptedModelBasedInverse::frequency_response(double omega) const {
  return correction_.frequency_response(omega) * inverse_.frequency_response(omega);
}

LinearBlock AdaptedModelBasedInverse::state_space() const {
  return series(correction_.state_space(), inverse_.state_space());
}

std::unique_ptr<Compensator> AdaptedModelBasedInverse::clone() const {
  return std::make_unique<AdaptedModelBasedInverse>(*this);
}

std::string AdaptedModelBasedInverse::describe() const {
  return inverse_.describe() + " with adaptive correction " + correction_.describe();
}

// ---------------------------------------------------------------------------------------------
}  // namespace rths::core
