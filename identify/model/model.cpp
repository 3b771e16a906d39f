#include "identify/model/model.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace rths::identify {
namespace {

double interpolate(std::span<const double> x, double pos) {
  if (pos <= 0.0) return x.front();
  const double last = static_cast<double>(x.size() - 1);
  if (pos >= last) return x.back();
  const auto i = static_cast<std::size_t>(pos);
  const double frac = pos - static_cast<double>(i);
  return x[i] + frac * (x[i + 1] - x[i]);
}

// Bouc–Wen (n = 1, beta = gamma = 1/2) advanced exactly over a drift increment s = dd / d_y:
// moving against z, dz/ds = 1 (linear back to zero); moving with z, dz/ds = 1 - |z| (saturating).
double advance_bouc_wen(double z, double s) {
  if (s < 0.0) return -advance_bouc_wen(-z, -s);
  if (z < 0.0) {
    if (s <= -z) return z + s;
    s += z;
    z = 0.0;
  }
  return 1.0 - (1.0 - z) * std::exp(-s);
}

}  // namespace

namespace {

// One model's parameter values by effect and name: the names and order are effect_params' (the
// one declaration of every parameter), so nothing here mirrors the layout by position.
class ParamValues {
 public:
  ParamValues(const ChannelModel& model, std::span<const double> p) : model_(model), p_(p) {
    const SignalScales names_only;  // the names and order do not depend on the scales
    for (const auto& spec : base_params(model.channel, names_only)) add(std::nullopt, spec.name);
    for (Effect e : model.effects) {
      for (const auto& spec : effect_params(e, model.channel, names_only)) add(e, spec.name);
    }
    if (p.size() != entries_.size()) {
      throw std::invalid_argument("parameter count does not match the model");
    }
  }
  // The named parameter of `effect` (of the base when empty); `absent` when the model lacks it.
  double at(std::optional<Effect> effect, const std::string& name, double absent) const {
    const auto i = index(effect, name);
    return i ? p_[*i] : absent;
  }
  // The kDriftTerms coefficients <prefix>_c1... of a slow drift; empty when the model lacks it.
  std::span<const double> drift(Effect effect, const std::string& prefix) const {
    const auto i = index(effect, prefix + "_c1");
    return i ? p_.subspan(*i, kDriftTerms) : std::span<const double>{};
  }
  bool has(Effect effect) const { return model_.has(effect); }

 private:
  struct Entry {
    std::optional<Effect> effect;
    std::string name;
  };
  void add(std::optional<Effect> effect, const std::string& name) {
    entries_.push_back({effect, name});
  }
  std::optional<std::size_t> index(std::optional<Effect> effect, const std::string& name) const {
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (entries_[i].effect == effect && entries_[i].name == name) return i;
    }
    return std::nullopt;
  }
  const ChannelModel& model_;
  std::span<const double> p_;
  std::vector<Entry> entries_;
};

// The record's normalised time s_j, the slow drifts D(s_j; c) on it and the shift both channels
// share: x(t_j - tau_j), tau_j = max(0, delay + D(s_j; delay_c)), interpolated.
class RecordClock {
 public:
  RecordClock(const ChannelSignals& sig, double delay, std::span<const double> delay_c)
      : sig_(sig),
        t_mid_(0.5 * (sig.time.front() + sig.time.back())),
        duration_(std::max(sig.time.back() - sig.time.front(), sig.dt)),
        has_basis_(sig.drift_basis.size() == sig.size() * kDriftTerms),
        delay_(delay),
        delay_c_(delay_c),
        constant_lag_(std::max(0.0, delay) / sig.dt) {}
  double s(std::size_t j) const { return (sig_.time[j] - t_mid_) / duration_; }
  // D(s_j; c), from the signals' precomputed basis when they carry one (same terms, same order).
  double drift(std::span<const double> c, std::size_t j) const {
    if (!has_basis_ || c.size() != kDriftTerms) return drift_profile(c, s(j));
    const double* row = sig_.drift_basis.data() + j * kDriftTerms;
    double sum = 0.0;
    for (std::size_t k = 0; k < kDriftTerms; ++k) sum += c[k] * row[k];
    return sum;
  }
  double shifted(std::span<const double> x, std::size_t j) const {
    if (delay_ == 0.0 && delay_c_.empty()) return x[j];
    const double lag =
        delay_c_.empty() ? constant_lag_ : std::max(0.0, delay_ + drift(delay_c_, j)) / sig_.dt;
    return interpolate(x, static_cast<double>(j) - lag);
  }

 private:
  const ChannelSignals& sig_;
  double t_mid_, duration_;
  bool has_basis_;
  double delay_;
  std::span<const double> delay_c_;
  // max(0, delay) / dt (samples) of a delay without a drift, divided once: the same value every
  // sample would divide again, as shifted() needs it up to four times a sample.
  double constant_lag_;
};

// Tustin biquad of wn^2 / (s^2 + 2 zeta wn s + wn^2) in direct form II transposed, pre-warp free
// (rates well below Nyquist), started at rest at x0 (DC gain 1: y = x0).
class SecondOrderLag {
 public:
  SecondOrderLag(double wn, double zeta, double dt, double x0) {
    const double K = 2.0 / dt;
    const double a0 = K * K + 2.0 * zeta * wn * K + wn * wn;
    b0_ = wn * wn / a0;
    b1_ = 2.0 * b0_;
    b2_ = b0_;
    a1_ = (2.0 * wn * wn - 2.0 * K * K) / a0;
    a2_ = (K * K - 2.0 * zeta * wn * K + wn * wn) / a0;
    s2_ = b2_ * x0 - a2_ * x0;
    s1_ = b1_ * x0 - a1_ * x0 + s2_;
  }
  double step(double x) {
    const double y = b0_ * x + s1_;
    s1_ = b1_ * x - a1_ * y + s2_;
    s2_ = b2_ * x - a2_ * y;
    return y;
  }

 private:
  double b0_ = 0.0, b1_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0, s1_ = 0.0, s2_ = 0.0;
};

// Channel measured (model.h): shift -> first order -> second order -> backlash -> saturation
// -> stroke -> gain (1 + D(s; gain_c)) + offset + drift s.
void predict_actuator(const ParamValues& v, const ChannelSignals& sig, std::vector<double>& out) {
  const RecordClock clock(sig, v.at(Effect::kDelay, "delay", 0.0),
                          v.drift(Effect::kTimeVaryingDelay, "delay"));
  const double gain = v.at(std::nullopt, "gain", 1.0);
  const double offset = v.at(Effect::kOffsetDrift, "offset", 0.0);
  const double drift = v.at(Effect::kOffsetDrift, "drift", 0.0);
  const std::span<const double> gain_c = v.drift(Effect::kTimeVaryingGain, "gain");
  const bool first = v.has(Effect::kFirstOrder), second = v.has(Effect::kSecondOrder);
  const bool play = v.has(Effect::kBacklash), saturate = v.has(Effect::kVelocitySaturation);
  const bool stroke = v.has(Effect::kStrokeLimit);
  const double end = std::abs(v.at(Effect::kStrokeLimit, "stroke", 0.0));
  const double time_constant = v.at(Effect::kFirstOrder, "time_constant", 0.0);
  const double decay = first ? std::exp(-sig.dt / std::max(time_constant, 1e-12)) : 0.0;
  const double x0 = clock.shifted(sig.input, 0);
  SecondOrderLag lag(v.at(Effect::kSecondOrder, "natural_frequency", 0.0),
                     v.at(Effect::kSecondOrder, "damping_ratio", 0.0), sig.dt, x0);
  double y1 = x0, play_out = x0, sat_out = x0;
  const double half_width = 0.5 * std::abs(v.at(Effect::kBacklash, "width", 0.0));
  const double max_step = std::abs(v.at(Effect::kVelocitySaturation, "max_velocity", 0.0)) * sig.dt;
  for (std::size_t j = 0; j < sig.size(); ++j) {
    double x = clock.shifted(sig.input, j);
    if (first) x = y1 = decay * y1 + (1.0 - decay) * x;
    if (second) x = lag.step(x);
    if (play) x = play_out = std::clamp(play_out, x - half_width, x + half_width);
    if (saturate) x = sat_out += std::clamp(x - sat_out, -max_step, max_step);
    if (stroke) x = std::clamp(x, -end, end);
    const double g = gain_c.empty() ? gain : gain * (1.0 + clock.drift(gain_c, j));
    out[j] = g * x + offset + drift * clock.s(j);
  }
}

// The last two sequences a thread computed, each for one signals' id and two parameters, reused
// when asked again for the same: friction tanh(v_j / v_c) and Bouc-Wen z_j depend on the delay
// and one parameter of their own only, so a Jacobian column of any other parameter finds the
// base run's sequence here (two slots: a column that moves them does not evict the base's).
class SequenceMemo {
 public:
  template <class Compute>
  const std::vector<double>& get(const ChannelSignals& sig, double a, double b, Compute compute) {
    for (Slot& slot : slots_) {
      if (sig.id != 0 && slot.id == sig.id && slot.a == a && slot.b == b &&
          slot.values.size() == sig.size()) {
        slot.used = ++clock_;
        return slot.values;
      }
    }
    Slot& slot = slots_[0].used <= slots_[1].used ? slots_[0] : slots_[1];
    slot.id = 0;
    slot.values.resize(sig.size());
    compute(slot.values);
    slot.id = sig.id;
    slot.a = a;
    slot.b = b;
    slot.used = ++clock_;
    return slot.values;
  }

 private:
  struct Slot {
    std::uint64_t id = 0, used = 0;
    double a = 0.0, b = 0.0;
    std::vector<double> values;
  };
  std::array<Slot, 2> slots_;
  std::uint64_t clock_ = 0;
};

// Channel force (model.h), on the low-passed displacement when there is one (make_signals).
void predict_specimen(const ParamValues& v, const ChannelSignals& sig, std::vector<double>& out) {
  const RecordClock clock(sig, v.at(Effect::kDelay, "delay", 0.0), {});
  const double k = v.at(Effect::kStiffness, "stiffness", 0.0);
  const double k3 = v.at(Effect::kCubicStiffness, "cubic_stiffness", 0.0);
  const double c = v.at(Effect::kDamping, "damping", 0.0);
  const double fc = v.at(Effect::kCoulomb, "friction_force", 0.0);
  const double mass = v.at(Effect::kInertia, "mass", 0.0);
  const double f_bw = v.at(Effect::kBoucWen, "hysteretic_force", 0.0);
  const double k_p = v.at(Effect::kElastoPlastic, "plastic_stiffness", 0.0);
  const double f_y = v.at(Effect::kElastoPlastic, "yield_force", 0.0);
  const double offset = v.at(Effect::kOffsetDrift, "offset", 0.0);
  const double drift = v.at(Effect::kOffsetDrift, "drift", 0.0);
  const std::span<const double> k_c = v.drift(Effect::kTimeVaryingStiffness, "stiffness");
  const bool bouc_wen = v.has(Effect::kBoucWen), elasto_plastic = v.has(Effect::kElastoPlastic);
  const double vc_safe =
      std::max(std::abs(v.at(Effect::kCoulomb, "smoothing_velocity", 1.0)), 1e-12);
  const double dy_safe = std::max(std::abs(v.at(Effect::kBoucWen, "yield_drift", 1.0)), 1e-12);
  const std::vector<double>& displacement = sig.model_input.empty() ? sig.input : sig.model_input;
  const double delay = v.at(Effect::kDelay, "delay", 0.0);
  thread_local SequenceMemo friction_memo, hysteresis_memo;
  const std::vector<double>& friction =
      fc == 0.0 ? displacement
                : friction_memo.get(sig, delay, vc_safe, [&](std::vector<double>& out) {
                    for (std::size_t j = 0; j < sig.size(); ++j) {
                      out[j] = std::tanh(clock.shifted(sig.velocity, j) / vc_safe);
                    }
                  });
  const std::vector<double>& hysteresis =
      !bouc_wen ? displacement
                : hysteresis_memo.get(sig, delay, dy_safe, [&](std::vector<double>& out) {
                    double z = 0.0, previous = clock.shifted(displacement, 0);
                    for (std::size_t j = 0; j < sig.size(); ++j) {
                      const double d = clock.shifted(displacement, j);
                      out[j] = z = advance_bouc_wen(z, (d - previous) / dy_safe);
                      previous = d;
                    }
                  });
  double plastic = 0.0;
  double previous_d = clock.shifted(displacement, 0);
  for (std::size_t j = 0; j < sig.size(); ++j) {
    const double d = clock.shifted(displacement, j);
    const double vel = clock.shifted(sig.velocity, j);
    const double s = clock.s(j);
    const double k_now = k_c.empty() ? k : k + clock.drift(k_c, j);
    double f = k_now * d + k3 * d * d * d + c * vel + offset + drift * s;
    if (fc != 0.0) f += fc * friction[j];
    if (mass != 0.0) f += mass * clock.shifted(sig.acceleration, j);
    if (bouc_wen) f += f_bw * hysteresis[j];
    if (elasto_plastic) {
      plastic = std::clamp(plastic + k_p * (d - previous_d), -std::abs(f_y), std::abs(f_y));
      f += plastic;
    }
    previous_d = d;
    out[j] = f;
  }
}

}  // namespace

void predict(const ChannelModel& model, std::span<const double> p, const ChannelSignals& sig,
             std::vector<double>& out) {
  const ParamValues values(model, p);
  out.assign(sig.size(), 0.0);
  if (sig.size() == 0) return;
  if (model.channel == Channel::kMeasured) {
    predict_actuator(values, sig, out);
  } else {
    predict_specimen(values, sig, out);
  }
}

std::vector<double> predict(const ChannelModel& model, const ChannelSignals& signals) {
  std::vector<double> out;
  predict(model, model.params, signals, out);
  return out;
}

double normalised_error(std::span<const double> target, std::span<const double> prediction,
                        std::span<const std::size_t> samples) {
  if (samples.empty() || prediction.size() != target.size()) {
    throw std::invalid_argument("normalised_error: no samples or different sizes");
  }
  double sum = 0.0, mean = 0.0;
  for (std::size_t i : samples) {
    const double r = target[i] - prediction[i];
    sum += r * r;
    mean += target[i];
  }
  const auto count = static_cast<double>(samples.size());
  mean /= count;
  double spread = 0.0;
  for (std::size_t i : samples) spread += (target[i] - mean) * (target[i] - mean);
  spread = std::sqrt(spread / count);
  const double rms = std::sqrt(sum / count);
  return spread > 0.0 ? rms / spread : rms;
}

}  // namespace rths::identify
