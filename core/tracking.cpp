#include "core/tracking.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <unsupported/Eigen/MatrixFunctions>

namespace rths::core {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& problem) {
  throw std::invalid_argument(field + ": " + problem);
}

// Parlett-Reinsch balancing by powers of two (exact): a <- D^-1 a D with the off-diagonal row and
// column norms of every state within a factor of two of each other; returns diag(D).
Vec balance(Mat& a) {
  const Eigen::Index n = a.rows();
  Vec d = Vec::Ones(n);
  for (bool done = false; !done;) {
    done = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      double column = a.col(i).cwiseAbs().sum() - std::abs(a(i, i));
      double row = a.row(i).cwiseAbs().sum() - std::abs(a(i, i));
      if (column == 0.0 || row == 0.0) continue;
      const double before = column + row;
      double f = 1.0;
      while (column < row / 2) column *= 2, row /= 2, f *= 2;
      while (column >= row * 2) column /= 2, row *= 2, f /= 2;
      if (column + row >= 0.95 * before) continue;  // column, row: the norms after the scaling
      done = false;
      d[i] *= f;
      a.row(i) /= f;
      a.col(i) *= f;
    }
  }
  return d;
}

// Characteristic polynomial det(sI - a), highest power first (Faddeev-LeVerrier).
std::vector<double> characteristic_polynomial(const Mat& a) {
  const Eigen::Index n = a.rows();
  std::vector<double> c(static_cast<std::size_t>(n + 1), 0.0);
  c[0] = 1.0;
  Mat m = Mat::Zero(n, n);
  for (Eigen::Index k = 1; k <= n; ++k) {
    m = a * m + c[static_cast<std::size_t>(k - 1)] * Mat::Identity(n, n);
    c[static_cast<std::size_t>(k)] = -(a * m).trace() / static_cast<double>(k);
  }
  return c;
}

}  // namespace

ContinuousTransferFunction state_space_transfer_function(const Mat& a, const Vec& b, const Vec& c,
                                                         double d) {
  const auto size = static_cast<std::size_t>(a.rows());
  const std::vector<double> den = characteristic_polynomial(a);
  const std::vector<double> coupled = characteristic_polynomial(a - b * c.transpose());
  ContinuousTransferFunction tf{std::vector<double>(size + 1), den};
  for (std::size_t i = 0; i <= size; ++i) tf.numerator[i] = coupled[i] - den[i] + d * den[i];
  return tf;
}

DiscreteFilter::DiscreteFilter() : b_{1.0}, a_{1.0}, state_(1, 0.0) {}

DiscreteFilter::DiscreteFilter(std::vector<double> b, std::vector<double> a)
    : b_(std::move(b)), a_(std::move(a)) {
  if (a_.empty() || b_.empty() || a_[0] == 0.0)
    throw std::invalid_argument("discrete filter: a[0] must be non-zero and b, a non-empty");
  const double a0 = a_[0];
  for (double& c : a_) c /= a0;
  for (double& c : b_) c /= a0;
  const std::size_t n = std::max(a_.size(), b_.size());
  a_.resize(n, 0.0);
  b_.resize(n, 0.0);
  state_.assign(n, 0.0);
}

double DiscreteFilter::step(double x) {
  // Direct form II transposed: y = b0 x + s0;  s_i = b_{i+1} x - a_{i+1} y + s_{i+1}.
  const double y = b_[0] * x + state_[0];
  const std::size_t n = a_.size() - 1;
  for (std::size_t i = 0; i < n; ++i)
    state_[i] = b_[i + 1] * x - a_[i + 1] * y + (i + 1 < n ? state_[i + 1] : 0.0);
  return y;
}

void DiscreteFilter::reset() { std::fill(state_.begin(), state_.end(), 0.0); }

std::complex<double> DiscreteFilter::response(std::complex<double> z) const {
  std::complex<double> num = 0.0, den = 0.0, power = 1.0;
  for (std::size_t i = 0; i < a_.size(); ++i, power /= z) {
    num += b_[i] * power;
    den += a_[i] * power;
  }
  return num / den;
}

ZohPlant::ZohPlant(const std::vector<double>& numerator, const std::vector<double>& denominator,
                   double h) {
  if (denominator.empty() || denominator.front() == 0.0 || numerator.size() >= denominator.size() ||
      !(h > 0))
    throw std::invalid_argument(
        "plant: a strictly proper num(s)/den(s) with den[0] != 0 and a step > 0 s is needed");
  const int n = static_cast<int>(denominator.size()) - 1;
  // Controllable canonical form of num/den normalised by den[0].
  Mat a = Mat::Zero(n, n);
  for (int i = 0; i + 1 < n; ++i) a(i, i + 1) = 1.0;
  for (int j = 0; j < n; ++j)
    a(n - 1, j) = -denominator[static_cast<std::size_t>(n - j)] / denominator[0];
  c_ = Eigen::RowVectorXd::Zero(n);
  for (std::size_t k = 0; k < numerator.size(); ++k)
    c_(static_cast<Eigen::Index>(numerator.size() - 1 - k)) = numerator[k] / denominator[0];
  // The companion form's entries span many decades (the benchmark plant's: 1 to 1e12), which the
  // exponential's scaling and squaring amplifies; a balanced realisation D^-1 A D keeps it exact.
  const Vec d = balance(a);
  c_ = c_.cwiseProduct(d.transpose());
  Mat augmented = Mat::Zero(n + 1, n + 1);
  augmented.topLeftCorner(n, n) = a;
  augmented(n - 1, n) = 1.0 / d[n - 1];
  const Mat e = (augmented * h).exp();
  ad_ = e.topLeftCorner(n, n);
  bd_ = e.block(0, n, n, 1);
  x_ = Vec::Zero(n);
  next_ = Vec::Zero(n);
}

void ZohPlant::advance(double u) {
  next_.noalias() = ad_ * x_;
  next_ += bd_ * u;
  x_.swap(next_);
}

std::complex<double> ZohPlant::response(std::complex<double> z) const {
  return response_at(state_space(), z);
}

LinearBlock ZohPlant::state_space() const {
  LinearBlock block;
  block.a = ad_;
  block.b = bd_;
  block.c = c_;
  block.d = 0.0;
  return block;
}

double Converter::analog_to_digital(double x) const {
  if (range > 0) x = std::clamp(x, -range, range);
  return quantum > 0 ? quantum * std::round(x / quantum) : x;
}

double Converter::digital_to_analog(double x) const {
  if (quantum > 0) x = quantum * std::round(x / quantum);
  return range > 0 ? std::clamp(x, -range, range) : x;
}

TrackingLoop::TrackingLoop(ZohPlant plant, const TrackingLoopOptions& options, double h,
                           const std::string& field)
    : plant_(std::move(plant)),
      controller_(options.controller.value_or(DiscreteFilter())),
      feedforward_(options.feedforward.value_or(DiscreteFilter())),
      converter_(options.converter),
      noise_rms_(options.displacement_noise_rms),
      h_(h),
      force_noise_rms_(options.force_noise_rms),
      seed_(options.seed),
      rng_(options.seed) {
  if (!(converter_.range >= 0 && converter_.quantum >= 0 && std::isfinite(converter_.range) &&
        std::isfinite(converter_.quantum)))
    fail(field + ".converter", "range and quantum must be >= 0 m (0 = none)");
  if (!(noise_rms_ >= 0 && std::isfinite(noise_rms_)))
    fail(field + ".displacement_noise_rms", "must be >= 0 m");
  if (!(force_noise_rms_ >= 0 && std::isfinite(force_noise_rms_)))
    fail(field + ".force_noise_rms", "must be >= 0 N");
  if (options.force_delay_periods > kMaxForceDelayPeriods)
    fail(field + ".force_delay_periods", std::to_string(options.force_delay_periods) +
                                             " is outside 0.." +
                                             std::to_string(kMaxForceDelayPeriods));
  force_queue_.assign(options.force_delay_periods + 1, 0.0);
  label_ = describe_loop(options);
  constexpr double w = 0.1;  // rad/s, well below every corner of a servo loop
  nominal_delay_ = -std::arg(response(w)) / w;
}

std::string TrackingLoop::describe_loop(const TrackingLoopOptions& options) const {
  std::ostringstream label;
  label << "tracking-loop(" << options.plant_name << (options.controller ? ", controller" : "")
        << (options.feedforward ? ", feedforward" : "")
        << (converter_.quantum > 0 || converter_.range > 0 ? ", converters" : "")
        << (noise_rms_ > 0 ? ", noise" : "") << (force_noise_rms_ > 0 ? ", force noise" : "")
        << (force_queue_.size() > 1 ? ", force delay " + std::to_string(force_queue_.size() - 1)
                                    : "")
        << ")";
  return label.str();
}

std::complex<double> TrackingLoop::response(double omega) const {
  const std::complex<double> z = std::exp(std::complex<double>(0.0, omega * h_));
  const std::complex<double> open = controller_.response(z) * plant_.response(z);
  return feedforward_.response(z) * open / (1.0 + open);
}

Linearity TrackingLoop::linearity() const {
  if (converter_.range > 0 || converter_.quantum > 0)
    return {Linearity::Kind::kLinearised, "its converters' saturation and quantisation left out"};
  return {};
}

std::complex<double> TrackingLoop::unscaled_response(double omega) const {
  const double periods = static_cast<double>(force_queue_.size() - 1);
  return response(omega) * std::exp(std::complex<double>(0.0, -omega * h_ * periods));
}

LinearBlock TrackingLoop::unscaled_state_space() const {
  // The closed loop from v (F's output) to x: e = v - C x, u = Cc s + Dc e, s+ = Ac s + Bc e,
  // x+ = Ad x + Bd (Cc s + Dc e), state [s, x].
  const LinearBlock c = controller_.state_space(), p = plant_.state_space();
  const int nc = c.states(), np = p.states();
  LinearBlock loop = zero_block(nc + np, 0.0);
  if (nc > 0) {
    loop.a.topLeftCorner(nc, nc) = c.a;
    loop.a.topRightCorner(nc, np) = -c.b * p.c;
    loop.a.bottomLeftCorner(np, nc) = p.b * c.c;
    loop.b.head(nc) = c.b;
  }
  loop.a.bottomRightCorner(np, np) = p.a - c.d * p.b * p.c;
  loop.b.tail(np) = c.d * p.b;
  loop.c.tail(np) = p.c;
  std::vector<double> register_taps(force_queue_.size() - 1, 0.0);
  if (!register_taps.empty()) register_taps.back() = 1.0;
  const LinearBlock force_delay = fir_block(register_taps.empty() ? 1.0 : 0.0, register_taps);
  return series(series(feedforward_.state_space(), loop), force_delay);
}

void TrackingLoop::reset() {
  plant_.reset();
  controller_.reset();
  feedforward_.reset();
  rng_.seed(seed_);
  normal_.reset();
  sensor_error_ = 0.0;
  std::fill(force_queue_.begin(), force_queue_.end(), 0.0);
  force_head_ = 0;
}

double TrackingLoop::measure_force(double force) {
  // The ring holds the readings of the last d + 1 periods; the slot written now is read d later.
  const double reading = force + (force_noise_rms_ > 0 ? force_noise_rms_ * normal_(rng_) : 0.0);
  force_queue_[force_head_] = reading;
  force_head_ = (force_head_ + 1) % force_queue_.size();
  return force_queue_[force_head_];
}

double TrackingLoop::step_unscaled(const CommandSample& in) {
  const double displacement = plant_.output();
  sensor_error_ = noise_rms_ > 0 ? noise_rms_ * normal_(rng_) : 0.0;
  const double measured = displacement + sensor_error_;
  const double target = converter_.digital_to_analog(
      feedforward_.step(converter_.analog_to_digital(in.displacement)));
  const double error = converter_.analog_to_digital(target - measured);
  plant_.advance(converter_.digital_to_analog(controller_.step(error)));
  return displacement;
}

}  // namespace rths::core
