#include "core/delay.h"

#include "core/number_text.h"
#include "core/time_text.h"

#include "core/compensator.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rths::core {
namespace {

// A block's description names its own parameters to 6 significant digits (%g), so that two
// blocks whose parameters differ read apart.
constexpr int kDescribedDigits = 6;

void require_positive_step(double dt, const char* who) {
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument(std::string(who) + ": time step dt must be > 0 and finite, got " +
                                std::to_string(dt));
  }
}

void require_non_negative_delay(double delay, const char* who) {
  if (!(delay >= 0.0) || !std::isfinite(delay)) {
    throw std::invalid_argument(std::string(who) + ": delay must be >= 0 and finite, got " +
                                std::to_string(delay));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
Linearity DelayStage::linearity() const {
  return {Linearity::Kind::kNone, "stage " + describe() + " does not state its linear dynamics"};
}

void DelayStage::require_analysable() const {
  const Linearity l = linearity();
  if (!l.analysable()) throw std::invalid_argument(describe() + ": " + l.note);
}

std::complex<double> DelayStage::unscaled_response(double omega) const {
  require_analysable();
  const std::optional<PlantModel> tf = unscaled_transfer_function();
  if (!tf) throw std::logic_error(describe() + ": a linear stage must state its response");
  return tf->at(omega);
}

LinearBlock DelayStage::unscaled_state_space() const {
  require_analysable();
  throw std::logic_error(describe() + ": a linear stage must state its realisation");
}

std::complex<double> DelayStage::frequency_response(double omega) const {
  return gain_ * unscaled_response(omega);
}

LinearBlock DelayStage::state_space() const {
  return series(unscaled_state_space(), gain_block(gain_));
}

std::optional<PlantModel> DelayStage::transfer_function() const {
  std::optional<PlantModel> tf = unscaled_transfer_function();
  if (tf) tf->gain *= gain_;
  return tf;
}

// ---------------------------------------------------------------------------------------------
std::unique_ptr<DelayStage> NoDelay::clone() const { return std::make_unique<NoDelay>(*this); }

// ---------------------------------------------------------------------------------------------
CommandHistory::CommandHistory(double max_lookback, double dt) {
  require_positive_step(dt, "CommandHistory");
  require_non_negative_delay(max_lookback, "CommandHistory (max_lookback)");
  // +3: the bracketing pair below t - lookback, the newest sample, and one for rounding.
  const double steps = std::ceil(max_lookback / dt);
  if (steps > 1e8) {
    throw std::invalid_argument("CommandHistory: looking back " + std::to_string(max_lookback) +
                                " s at dt = " + std::to_string(dt) +
                                " s needs more than 1e8 samples");
  }
  const std::size_t capacity = static_cast<std::size_t>(steps) + 3;
  times_.assign(capacity, 0.0);
  values_.assign(capacity, 0.0);
}

void CommandHistory::push(double time, double value) {
  head_ = (head_ + 1) % times_.size();
  times_[head_] = time;
  values_[head_] = value;
  size_ = std::min(size_ + 1, times_.size());
}

double CommandHistory::at(double time) const {
  if (size_ == 0) return 0.0;  // at rest before any command
  const std::size_t capacity = times_.size();
  // Logical index 0 = oldest kept sample, size_ - 1 = newest.
  const auto slot = [&](std::size_t logical) {
    return (head_ + capacity - (size_ - 1) + logical) % capacity;
  };
  const std::size_t newest = slot(size_ - 1);
  if (time >= times_[newest]) return values_[newest];
  const std::size_t oldest = slot(0);
  if (time <= times_[oldest]) return values_[oldest];
  // Binary search for the last sample with t <= time; times are increasing.
  std::size_t lo = 0, hi = size_ - 1;  // times(lo) < time < times(hi)
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (times_[slot(mid)] <= time) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const std::size_t a = slot(lo), b = slot(hi);
  const double span = times_[b] - times_[a];
  if (!(span > 0.0)) return values_[b];
  const double w = (time - times_[a]) / span;
  return values_[a] + w * (values_[b] - values_[a]);
}

void CommandHistory::clear() {
  head_ = 0;
  size_ = 0;
}

// ---------------------------------------------------------------------------------------------
TimeShift::TimeShift(double delay, double dt)
    : delay_((require_non_negative_delay(delay, "TimeShift"), delay)),
      dt_(dt),
      history_(delay, dt) {}

std::optional<PlantModel> TimeShift::unscaled_transfer_function() const {
  PlantModel shift;
  shift.delay = delay_;
  return shift;
}

std::unique_ptr<DelayStage> TimeShift::clone() const { return std::make_unique<TimeShift>(*this); }

std::string TimeShift::describe() const {
  return "shift(" + format_ms(delay_, kDescribedDigits) + ")";
}

double TimeShift::step_unscaled(const CommandSample& in) {
  history_.push(in.time, in.displacement);
  return history_.at(in.time - delay_);
}

// ---------------------------------------------------------------------------------------------
std::unique_ptr<DelayStage> Eq1Lead::clone() const { return std::make_unique<Eq1Lead>(*this); }
std::string Eq1Lead::describe() const {
  return "eq1(u + v*" + format_ms(delay_, kDescribedDigits) + ", lead as printed)";
}

std::unique_ptr<DelayStage> Eq1Lag::clone() const { return std::make_unique<Eq1Lag>(*this); }
std::string Eq1Lag::describe() const {
  return "eq1-lag(u - v*" + format_ms(delay_, kDescribedDigits) + ")";
}

namespace {
constexpr const char* kReadsVelocity =
    "it reads the command's velocity, which a single-input linear block has not";
}  // namespace

Linearity Eq1Lead::linearity() const { return {Linearity::Kind::kNone, kReadsVelocity}; }
Linearity Eq1Lag::linearity() const { return {Linearity::Kind::kNone, kReadsVelocity}; }

// ---------------------------------------------------------------------------------------------
FirstOrderActuator::FirstOrderActuator(double time_constant, double dt)
    : time_constant_(time_constant), decay_(0.0) {
  require_positive_step(dt, "FirstOrderActuator");
  if (!(time_constant > 0.0) || !std::isfinite(time_constant)) {
    throw std::invalid_argument("FirstOrderActuator: time constant must be > 0, got " +
                                std::to_string(time_constant));
  }
  decay_ = std::exp(-dt / time_constant);
}

std::unique_ptr<DelayStage> FirstOrderActuator::clone() const {
  return std::make_unique<FirstOrderActuator>(*this);
}

std::string FirstOrderActuator::describe() const {
  return "first-order(T = " + format_ms(time_constant_, kDescribedDigits) + ")";
}

std::optional<PlantModel> FirstOrderActuator::unscaled_transfer_function() const {
  PlantModel lag;
  lag.append({1.0}, {time_constant_, 1.0});
  return lag;
}

LinearBlock FirstOrderActuator::unscaled_state_space() const {
  LinearBlock block;
  block.a = Mat::Constant(1, 1, decay_);
  block.b = Vec::Constant(1, 1.0 - decay_);
  block.c = Eigen::RowVectorXd::Constant(1, decay_);
  block.d = 1.0 - decay_;
  return block;
}

double FirstOrderActuator::step_unscaled(const CommandSample& in) {
  state_ = decay_ * state_ + (1.0 - decay_) * in.displacement;
  return state_;
}

// ---------------------------------------------------------------------------------------------
JitterShift::JitterShift(double mean_delay, double std_dev, std::uint64_t seed, double dt)
    : mean_((require_non_negative_delay(mean_delay, "JitterShift (mean)"), mean_delay)),
      std_dev_((require_non_negative_delay(std_dev, "JitterShift (standard deviation)"), std_dev)),
      cap_(mean_delay + 6.0 * std_dev),
      seed_(seed),
      rng_(seed),
      history_(mean_delay + 6.0 * std_dev, dt) {}

void JitterShift::reset() {
  rng_.seed(seed_);
  normal_.reset();
  history_.clear();
  last_delay_ = 0.0;
}

std::unique_ptr<DelayStage> JitterShift::clone() const {
  return std::make_unique<JitterShift>(*this);
}

std::string JitterShift::describe() const {
  return "jitter(mean " + format_ms(mean_, kDescribedDigits) + ", sd " +
         format_ms(std_dev_, kDescribedDigits) + ", seed " + std::to_string(seed_) + ")";
}

Linearity JitterShift::linearity() const {
  return {Linearity::Kind::kNone, "its delay is redrawn every step (time-varying)"};
}

double JitterShift::step_unscaled(const CommandSample& in) {
  history_.push(in.time, in.displacement);
  // One draw every step, whatever the value, so the sequence depends only on the seed and the
  // step count.
  const double draw = normal_(rng_);
  last_delay_ = std::clamp(mean_ + std_dev_ * draw, 0.0, cap_);
  return history_.at(in.time - last_delay_);
}

// ---------------------------------------------------------------------------------------------
double DelayTrace::at(double t) const {
  if (time.empty()) return 0.0;
  if (t <= time.front()) return delay.front();
  if (t >= time.back()) return delay.back();
  const auto upper = std::upper_bound(time.begin(), time.end(), t);
  const std::size_t hi = static_cast<std::size_t>(upper - time.begin());
  const std::size_t lo = hi - 1;
  const double w = (t - time[lo]) / (time[hi] - time[lo]);
  return delay[lo] + w * (delay[hi] - delay[lo]);
}

double DelayTrace::max() const {
  return delay.empty() ? 0.0 : *std::max_element(delay.begin(), delay.end());
}

TraceShift::TraceShift(DelayTrace trace, double dt)
    : trace_(std::move(trace)), history_(trace_.max(), dt) {
  if (trace_.time.empty() || trace_.time.size() != trace_.delay.size()) {
    throw std::invalid_argument("TraceShift: the trace is empty or its columns differ in length");
  }
}

std::unique_ptr<DelayStage> TraceShift::clone() const {
  return std::make_unique<TraceShift>(*this);
}

std::string TraceShift::describe() const {
  return "trace(" + std::to_string(trace_.time.size()) + " samples, mean " +
         format_ms(nominal_delay(), kDescribedDigits) + ", max " +
         format_ms(trace_.max(), kDescribedDigits) + ")";
}

double TraceShift::nominal_delay() const {
  double sum = 0.0;
  for (double d : trace_.delay) sum += d;
  return sum / static_cast<double>(trace_.delay.size());
}

Linearity TraceShift::linearity() const {
  return {Linearity::Kind::kNone, "its delay follows a recorded trace (time-varying)"};
}

double TraceShift::step_unscaled(const CommandSample& in) {
  history_.push(in.time, in.displacement);
  return history_.at(in.time - trace_.at(in.time));
}

// ---------------------------------------------------------------------------------------------
DelayChain::DelayChain() = default;
DelayChain::~DelayChain() = default;
DelayChain::DelayChain(DelayChain&&) noexcept = default;
DelayChain& DelayChain::operator=(DelayChain&&) noexcept = default;

DelayChain::DelayChain(const DelayChain& other)
    : compensator_(other.compensator_ ? other.compensator_->clone() : nullptr),
      measured_(other.measured_) {
  stages_.reserve(other.stages_.size());
  for (const auto& stage : other.stages_) stages_.push_back(stage->clone());
}

DelayChain& DelayChain::operator=(const DelayChain& other) {
  if (this != &other) *this = DelayChain(other);
  return *this;
}

void DelayChain::set_compensator(std::unique_ptr<Compensator> compensator) {
  compensator_ = std::move(compensator);
}

double DelayChain::step(const CommandSample& in) {
  CommandSample sample = in;
  if (compensator_) {
    sample.displacement = compensator_->step({in.time, in.displacement, measured_});
  }
  for (auto& stage : stages_) sample.displacement = stage->step(sample);
  measured_ = sample.displacement;
  for (const auto& stage : stages_) measured_ += stage->sensor_error();
  return sample.displacement;
}

double DelayChain::measure_force(double force) {
  for (auto& stage : stages_) force = stage->measure_force(force);
  return force;
}

void DelayChain::reset() {
  for (auto& stage : stages_) stage->reset();
  if (compensator_) compensator_->reset();
  measured_ = 0.0;
}

double DelayChain::nominal_delay() const {
  double sum = 0.0;
  for (const auto& stage : stages_) sum += stage->nominal_delay();
  if (compensator_) sum -= compensator_->nominal_lead();
  return sum;
}

std::string DelayChain::describe() const {
  if (empty()) return "none";
  std::string text = compensator_ ? "compensation " + compensator_->describe() : std::string();
  for (const auto& stage : stages_) {
    if (!text.empty()) text += " -> ";
    text += stage->describe();
    if (stage->gain() != 1.0) {
      text += " x" + format_number(stage->gain());
    }
  }
  return text;
}

// ---------------------------------------------------------------------------------------------
namespace {

int severity(Linearity::Kind kind) {
  switch (kind) {
    case Linearity::Kind::kTimeInvariant: return 0;
    case Linearity::Kind::kFrozen: return 1;
    case Linearity::Kind::kLinearised: return 2;
    case Linearity::Kind::kNone: return 3;
  }
  return 3;
}

// Folds one block's linearity into the chain's, naming the block in its note.
void fold_linearity(Linearity& chain, const Linearity& block, const std::string& name) {
  if (block.kind == Linearity::Kind::kTimeInvariant) return;
  if (severity(block.kind) > severity(chain.kind)) {
    if (block.kind == Linearity::Kind::kNone) chain.note.clear();
    chain.kind = block.kind;
  } else if (chain.kind == Linearity::Kind::kNone) {
    return;  // the first block that cannot be represented is the one named
  }
  chain.note += (chain.note.empty() ? "" : "; ") + name + ": " + block.note;
}

}  // namespace

Linearity DelayChain::linearity() const {
  Linearity chain;
  if (compensator_)
    fold_linearity(chain, compensator_->linearity(), "compensator " + compensator_->describe());
  for (std::size_t i = 0; i < stages_.size(); ++i)
    fold_linearity(chain, stages_[i]->linearity(),
                   "delay stage " + std::to_string(i + 1) + " " + stages_[i]->describe());
  return chain;
}

std::complex<double> DelayChain::frequency_response(double omega) const {
  PlantModel rational;
  std::vector<const DelayStage*> others;
  for (const auto& stage : stages_) {
    if (const std::optional<PlantModel> tf = stage->transfer_function())
      rational.append(*tf);
    else
      others.push_back(stage.get());
  }
  std::complex<double> h = rational.at(omega);
  for (const DelayStage* stage : others) h *= stage->frequency_response(omega);
  if (compensator_) h *= compensator_->frequency_response(omega);
  return h;
}

LinearBlock DelayChain::state_space() const {
  LinearBlock loop = gain_block(1.0);
  for (const auto& stage : stages_) loop = series(loop, stage->state_space());
  if (compensator_) loop = series(compensator_->state_space(), loop);
  return loop;
}

}  // namespace rths::core
