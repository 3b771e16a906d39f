#include "identify/model.h"

#include "identify/evidence.h"

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

struct EffectInfo {
  Effect effect;
  const char* name;
  bool measured, force;
};

constexpr std::array<EffectInfo, 16> kEffects{{
    {Effect::kDelay, "delay", true, true},
    {Effect::kOffsetDrift, "offset_drift", true, true},
    {Effect::kFirstOrder, "first_order", true, false},
    {Effect::kSecondOrder, "second_order", true, false},
    {Effect::kBacklash, "backlash", true, false},
    {Effect::kVelocitySaturation, "velocity_saturation", true, false},
    {Effect::kTimeVaryingDelay, "time_varying_delay", true, false},
    {Effect::kTimeVaryingGain, "time_varying_gain", true, false},
    {Effect::kStiffness, "stiffness", false, true},
    {Effect::kDamping, "damping", false, true},
    {Effect::kCoulomb, "coulomb_friction", false, true},
    {Effect::kBoucWen, "bouc_wen", false, true},
    {Effect::kCubicStiffness, "cubic_stiffness", false, true},
    {Effect::kTimeVaryingStiffness, "time_varying_stiffness", false, true},
    {Effect::kInertia, "inertia", false, true},
    {Effect::kElastoPlastic, "elastoplastic", false, true},
}};

const EffectInfo& info(Effect effect) {
  for (const auto& e : kEffects) {
    if (e.effect == effect) return e;
  }
  throw std::logic_error("effect without info");
}

double rms_about_mean(std::span<const double> x) {
  if (x.empty()) return 0.0;
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
  double sum = 0.0;
  for (double v : x) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / static_cast<double>(x.size()));
}

// Value of x at fractional sample index `pos`, held at the ends.
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

std::vector<double> moving_average(std::span<const double> x, std::size_t window) {
  const std::size_t n = x.size();
  std::vector<double> out(n);
  if (window <= 1) {
    std::copy(x.begin(), x.end(), out.begin());
    return out;
  }
  const std::size_t half = window / 2;
  std::vector<double> prefix(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + x[i];
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t lo = i >= half ? i - half : 0;
    const std::size_t hi = std::min(n, i + half + 1);
    out[i] = (prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo);
  }
  return out;
}

std::vector<double> central_difference(std::span<const double> x, double dt) {
  const std::size_t n = x.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  for (std::size_t i = 1; i + 1 < n; ++i) d[i] = (x[i + 1] - x[i - 1]) / (2.0 * dt);
  d[0] = (x[1] - x[0]) / dt;
  d[n - 1] = (x[n - 1] - x[n - 2]) / dt;
  return d;
}

ParamSpec param_spec(std::string name, std::string unit, double scale, double lower, double upper,
                     std::vector<double> guesses) {
  ParamSpec spec;
  spec.name = std::move(name);
  spec.unit = std::move(unit);
  spec.scale = scale;
  spec.lower = lower;
  spec.upper = upper;
  spec.guesses = std::move(guesses);
  return spec;
}

// kDriftTerms coefficients named <prefix>_c1 ... with the given scale and symmetric bound.
std::vector<ParamSpec> drift_params(const std::string& prefix, const std::string& unit,
                                    double scale, double bound) {
  std::vector<ParamSpec> out;
  for (std::size_t k = 1; k <= kDriftTerms; ++k) {
    ParamSpec spec =
        param_spec(prefix + "_c" + std::to_string(k), unit, scale, -bound, bound, {0.0});
    spec.record_specific = true;
    out.push_back(std::move(spec));
  }
  return out;
}

ParamSpec non_negative(ParamSpec spec, const std::string& below_means) {
  spec.lower = 0.0;
  spec.below_means = below_means;
  return spec;
}

}  // namespace

double drift_profile(std::span<const double> c, double s) {
  double sum = 0.0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    sum += c[k] * std::cos(std::numbers::pi * static_cast<double>(k + 1) * (s + 0.5));
  }
  return sum;
}

std::vector<double> drift_basis(std::span<const double> time, double dt) {
  std::vector<double> basis(time.size() * kDriftTerms);
  if (time.empty()) return basis;
  const double t_mid = 0.5 * (time.front() + time.back());
  const double duration = std::max(time.back() - time.front(), dt);
  for (std::size_t j = 0; j < time.size(); ++j) {
    const double s = (time[j] - t_mid) / duration;
    for (std::size_t k = 0; k < kDriftTerms; ++k) {
      basis[j * kDriftTerms + k] =
          std::cos(std::numbers::pi * static_cast<double>(k + 1) * (s + 0.5));
    }
  }
  return basis;
}

std::string channel_name(Channel channel) {
  return channel == Channel::kMeasured ? "measured" : "force";
}

std::string effect_name(Effect effect) { return info(effect).name; }

Effect parse_effect(const std::string& name) {
  for (const auto& e : kEffects) {
    if (name == e.name) return e.effect;
  }
  std::string names;
  for (const auto& e : kEffects) names += (names.empty() ? "" : ", ") + std::string(e.name);
  throw std::invalid_argument("unknown effect '" + name + "' (known: " + names + ")");
}

bool effect_applies(Effect effect, Channel channel) {
  const auto& e = info(effect);
  return channel == Channel::kMeasured ? e.measured : e.force;
}

std::vector<Effect> effect_library(Channel channel) {
  std::vector<Effect> out;
  for (const auto& e : kEffects) {
    if (effect_applies(e.effect, channel)) out.push_back(e.effect);
  }
  return out;
}

std::vector<double> zero_phase_lowpass(std::span<const double> x, double dt, double cutoff) {
  if (!(dt > 0.0) || !(cutoff > 0.0) || !(cutoff < 0.5 / dt)) {
    throw std::invalid_argument("zero_phase_lowpass: need 0 < cutoff < Nyquist (cutoff " +
                                std::to_string(cutoff) + " Hz, dt " + std::to_string(dt) + " s)");
  }
  std::vector<double> y(x.begin(), x.end());
  if (y.empty()) return y;
  const double w = std::tan(std::numbers::pi * cutoff * dt);  // pre-warped analogue cut-off
  const auto section = [&](double q) {
    const double norm = 1.0 / (1.0 + w / q + w * w);
    const double b0 = w * w * norm, b1 = 2.0 * b0, b2 = b0;
    const double a1 = 2.0 * (w * w - 1.0) * norm, a2 = (1.0 - w / q + w * w) * norm;
    // Direct form II transposed, at rest with input y[0] (DC gain 1).
    double s2 = (b2 - a2) * y.front();
    double s1 = (b1 - a1) * y.front() + s2;
    for (double& v : y) {
      const double out = b0 * v + s1;
      s1 = b1 * v - a1 * out + s2;
      s2 = b2 * v - a2 * out;
      v = out;
    }
  };
  const double q1 = 1.0 / (2.0 * std::cos(std::numbers::pi / 8.0));
  const double q2 = 1.0 / (2.0 * std::cos(3.0 * std::numbers::pi / 8.0));
  for (int pass = 0; pass < 2; ++pass) {
    section(q1);
    section(q2);
    std::reverse(y.begin(), y.end());
  }
  return y;
}

ChannelSignals make_signals(const MeasuredData& data, Channel channel, double smooth_window) {
  ChannelSignals s;
  s.channel = channel;
  s.dt = data.dt;
  s.time = data.time;
  s.input = channel == Channel::kMeasured ? data.command : data.measured;
  s.target = channel == Channel::kMeasured ? data.measured : data.force;
  if (channel == Channel::kForce && s.input.size() >= 16) {
    const double edge = noise_edge(s.input, data.dt);
    const double cutoff =
        edge > 0.0 ? std::max(kSpecimenInputCutoffFactor * signal_band(s.input, data.dt), edge)
                   : 0.0;
    if (cutoff > 0.0 && cutoff < 0.8 * 0.5 / data.dt) {
      s.model_input = zero_phase_lowpass(s.input, data.dt, cutoff);
      s.input_cutoff = cutoff;
    }
  }
  const std::vector<double>& drive = s.model_input.empty() ? s.input : s.model_input;
  const auto window = static_cast<std::size_t>(std::max(1.0, std::round(smooth_window / data.dt)));
  const auto smooth = moving_average(drive, window);
  s.velocity = central_difference(smooth, data.dt);
  s.acceleration = central_difference(moving_average(s.velocity, window), data.dt);
  s.drift_basis = drift_basis(s.time, s.dt);
  static std::atomic<std::uint64_t> next_id{1};
  s.id = next_id.fetch_add(1);
  return s;
}

SignalScales signal_scales(const ChannelSignals& signals) {
  SignalScales sc;
  const auto positive = [](double v, double fallback) { return v > 0.0 ? v : fallback; };
  sc.input = positive(rms_about_mean(signals.input), 1.0e-3);
  sc.velocity = positive(rms_about_mean(signals.velocity), sc.input);
  sc.acceleration = positive(rms_about_mean(signals.acceleration), sc.velocity);
  sc.target = positive(rms_about_mean(signals.target), 1.0);
  sc.dt = signals.dt;
  sc.duration = signals.size() > 1 ? signals.time.back() - signals.time.front() : 1.0;
  if (!(sc.duration > 0.0)) sc.duration = 1.0;
  return sc;
}

std::vector<ParamSpec> base_params(Channel channel, const SignalScales&) {
  if (channel == Channel::kMeasured) return {param_spec("gain", "-", 1.0, 0.0, 10.0, {1.0})};
  return {};
}

std::vector<ParamSpec> effect_params(Effect effect, Channel channel, const SignalScales& sc) {
  if (!effect_applies(effect, channel)) {
    throw std::invalid_argument("effect '" + effect_name(effect) + "' does not apply to channel '" +
                                channel_name(channel) + "'");
  }
  const bool measured = channel == Channel::kMeasured;
  const double out_scale = measured ? sc.input : sc.target;
  const double k_scale = sc.target / sc.input;
  switch (effect) {
    case Effect::kDelay: {
      const double longest = std::min(1.0, 0.5 * sc.duration);
      if (!measured) {
        // The force's delay behind the measured displacement is a skew between two transducers'
        // conditioning, of either sign (the displacement's filter may be the slower one).
        return {param_spec("delay", "s", 0.01, -0.02, longest, {0.0, 0.002})};
      }
      const ParamSpec delay = param_spec("delay", "s", 0.01, 0.0, longest, {0.0, 0.005, 0.02});
      return {non_negative(delay, "a negative delay (a lead)")};
    }
    case Effect::kOffsetDrift: {
      ParamSpec offset =
          param_spec("offset", measured ? "m" : "N", out_scale, -1e300, 1e300, {0.0});
      ParamSpec drift = param_spec("drift", measured ? "m" : "N", out_scale, -1e300, 1e300, {0.0});
      offset.record_specific = drift.record_specific = true;
      return {offset, drift};
    }
    case Effect::kFirstOrder:
      return {param_spec("time_constant", "s", 0.01, 0.2 * sc.dt, 1.0, {0.005, 0.03})};
    case Effect::kSecondOrder:
      return {param_spec("natural_frequency", "rad/s", 100.0, 2.0 * std::numbers::pi * 0.2,
                         std::numbers::pi / sc.dt,
                         {2.0 * std::numbers::pi * 5.0, 2.0 * std::numbers::pi * 20.0}),
              param_spec("damping_ratio", "-", 1.0, 0.05, 5.0, {0.7})};
    case Effect::kBacklash:
      return {non_negative(param_spec("width", "m", 0.05 * sc.input, 0.0, 10.0 * sc.input,
                                      {0.03 * sc.input, 0.2 * sc.input}),
                           "a negative backlash width")};
    case Effect::kVelocitySaturation:
      return {param_spec("max_velocity", "m/s", sc.velocity, 0.01 * sc.velocity, 1e300,
                         {0.8 * sc.velocity, 2.0 * sc.velocity})};
    case Effect::kTimeVaryingDelay: return drift_params("delay", "s", 0.005, 0.1);
    case Effect::kTimeVaryingGain: return drift_params("gain", "-", 0.02, 0.5);
    case Effect::kStiffness:
      return {non_negative(param_spec("stiffness", "N/m", k_scale, 0.0, 1e300, {0.0}),
                           "a negative stiffness")};
    case Effect::kDamping:
      return {
          non_negative(param_spec("damping", "N s/m", sc.target / sc.velocity, 0.0, 1e300, {0.0}),
                       "a negative damping")};
    case Effect::kCoulomb:
      return {non_negative(param_spec("friction_force", "N", sc.target, 0.0, 1e300, {0.0}),
                           "a negative friction force"),
              param_spec("smoothing_velocity", "m/s", 0.1 * sc.velocity, 1e-4 * sc.velocity,
                         10.0 * sc.velocity, {0.02 * sc.velocity, 0.2 * sc.velocity})};
    case Effect::kBoucWen:
      return {non_negative(param_spec("hysteretic_force", "N", sc.target, 0.0, 1e300, {0.0}),
                           "a negative hysteretic force"),
              param_spec("yield_drift", "m", 0.1 * sc.input, 1e-4 * sc.input, 10.0 * sc.input,
                         {0.02 * sc.input, 0.2 * sc.input})};
    case Effect::kCubicStiffness:
      return {param_spec("cubic_stiffness", "N/m^3", sc.target / std::pow(sc.input, 3), -1e300,
                         1e300, {0.0})};
    case Effect::kTimeVaryingStiffness:
      return drift_params("stiffness", "N/m", 0.05 * k_scale, 1e300);
    case Effect::kInertia:
      return {non_negative(param_spec("mass", "kg", sc.target / sc.acceleration, 0.0, 1e300, {0.0}),
                           "a negative mass")};
    case Effect::kElastoPlastic:
      return {non_negative(param_spec("plastic_stiffness", "N/m", k_scale, 0.0, 1e300,
                                      {k_scale, 5.0 * k_scale}),
                           "a negative elastic stiffness"),
              non_negative(param_spec("yield_force", "N", sc.target, 0.0, 1e300,
                                      {0.3 * sc.target, 1.0 * sc.target}),
                           "a negative yield force")};
  }
  throw std::logic_error("unhandled effect");
}

bool ChannelModel::has(Effect effect) const {
  return std::find(effects.begin(), effects.end(), effect) != effects.end();
}

std::vector<ParamSpec> declared_specs(std::vector<ParamSpec> specs,
                                      const std::vector<ParamDeclaration>& declarations) {
  for (auto& spec : specs) {
    for (const auto& d : declarations) {
      if (d.name != spec.name) continue;
      if (d.lower && *d.lower > spec.lower) {
        spec.lower = *d.lower;
        spec.below_means.clear();
      }
      if (d.upper && *d.upper < spec.upper) spec.upper = *d.upper;
      // Only reachable at a decimated search rate whose Nyquist is below a declared minimum.
      if (spec.lower > spec.upper) spec.upper = spec.lower;
      if (d.initial) spec.guesses = {std::clamp(*d.initial, spec.lower, spec.upper)};
      spec.fixed = spec.fixed || d.fixed;
    }
  }
  return specs;
}

std::vector<ParamSpec> ChannelModel::specs(const SignalScales& scales) const {
  auto out = base_params(channel, scales);
  for (Effect e : effects) {
    auto more = effect_params(e, channel, scales);
    out.insert(out.end(), more.begin(), more.end());
  }
  out = declared_specs(std::move(out), declarations);
  for (std::size_t i = 0; i < out.size(); ++i) out[i].fixed = out[i].fixed || is_fixed(i);
  return out;
}

std::optional<double> ChannelModel::param(std::optional<Effect> effect, const std::string& name,
                                          const SignalScales& scales) const {
  const auto index = index_of(effect, name, scales);
  if (!index) return std::nullopt;
  return params.at(*index);
}

std::optional<std::size_t> ChannelModel::index_of(std::optional<Effect> effect,
                                                  const std::string& name,
                                                  const SignalScales& scales) const {
  const auto base = base_params(channel, scales);
  if (!effect) {
    for (std::size_t i = 0; i < base.size(); ++i) {
      if (base[i].name == name) return i;
    }
    return std::nullopt;
  }
  std::size_t index = base.size();
  for (Effect e : effects) {
    const auto p = effect_params(e, channel, scales);
    if (e == *effect) {
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (p[i].name == name) return index + i;
      }
      return std::nullopt;
    }
    index += p.size();
  }
  return std::nullopt;
}

std::optional<Effect> ChannelModel::effect_of(std::size_t index, const SignalScales& scales) const {
  std::size_t first = base_params(channel, scales).size();
  if (index < first) return std::nullopt;
  for (Effect e : effects) {
    const std::size_t count = effect_params(e, channel, scales).size();
    if (index < first + count) return e;
    first += count;
  }
  throw std::out_of_range("parameter index beyond the model");
}

std::string ChannelModel::describe(const SignalScales& scales) const {
  std::ostringstream out;
  const auto s = specs(scales);
  out << channel_name(channel) << ":";
  for (Effect e : effects) out << " " << effect_name(e);
  out << " {";
  for (std::size_t i = 0; i < s.size(); ++i) {
    out << (i ? ", " : "") << s[i].name << "=" << params[i] << " " << s[i].unit;
  }
  out << "}";
  return out.str();
}

namespace {

// The value of a parameter that leaves the output as it is without its effect: zero, within the
// bounds, except for dynamics (a zero time constant or a finite frequency would not be neutral),
// a velocity limit (far above the record's velocities) and a smoothing scale (its first guess).
double neutral_value(const ParamSpec& spec, const SignalScales& scales) {
  if (spec.name == "time_constant") return spec.lower;
  if (spec.name == "natural_frequency") return 0.5 * spec.upper;
  if (spec.name == "damping_ratio") return 0.7;
  if (spec.name == "max_velocity") return 1e3 * scales.velocity;
  if (spec.name == "smoothing_velocity" || spec.name == "yield_drift") return spec.guesses.at(0);
  return std::clamp(0.0, spec.lower, spec.upper);
}

}  // namespace

ChannelModel declared_model(Channel channel, const std::vector<Effect>& effects,
                            const SignalScales& scales) {
  ChannelModel model;
  model.channel = channel;
  for (const auto& spec : base_params(channel, scales)) model.params.push_back(spec.guesses[0]);
  for (Effect e : effects) {
    if (model.has(e)) continue;
    std::vector<double> neutral;
    for (const auto& spec : effect_params(e, channel, scales)) {
      neutral.push_back(neutral_value(spec, scales));
    }
    model = with_effect(model, e, neutral);
  }
  return model;
}

ChannelModel with_effect(const ChannelModel& model, Effect effect, std::span<const double> guess) {
  if (model.has(effect)) {
    throw std::invalid_argument("model already has effect '" + effect_name(effect) + "'");
  }
  ChannelModel out = model;
  out.effects.push_back(effect);
  out.params.insert(out.params.end(), guess.begin(), guess.end());
  if (!out.fixed.empty()) out.fixed.resize(out.params.size(), false);
  return out;
}

ChannelModel without_effect(const ChannelModel& model, Effect effect, const SignalScales& scales) {
  if (!model.has(effect)) {
    throw std::invalid_argument("model has no effect '" + effect_name(effect) + "'");
  }
  ChannelModel out;
  out.channel = model.channel;
  out.declarations = model.declarations;
  std::size_t index = base_params(model.channel, scales).size();
  for (std::size_t i = 0; i < index; ++i) {
    out.params.push_back(model.params[i]);
    out.fixed.push_back(model.is_fixed(i));
  }
  for (Effect e : model.effects) {
    const std::size_t count = effect_params(e, model.channel, scales).size();
    if (e != effect) {
      out.effects.push_back(e);
      for (std::size_t i = index; i < index + count; ++i) {
        out.params.push_back(model.params[i]);
        out.fixed.push_back(model.is_fixed(i));
      }
    }
    index += count;
  }
  return out;
}

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
        delay_c_(delay_c) {}
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
    const double tau = std::max(0.0, delay_ + (delay_c_.empty() ? 0.0 : drift(delay_c_, j)));
    return interpolate(x, static_cast<double>(j) - tau / sig_.dt);
  }

 private:
  const ChannelSignals& sig_;
  double t_mid_, duration_;
  bool has_basis_;
  double delay_;
  std::span<const double> delay_c_;
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
// -> gain (1 + D(s; gain_c)) + offset + drift s.
void predict_actuator(const ParamValues& v, const ChannelSignals& sig, std::vector<double>& out) {
  const RecordClock clock(sig, v.at(Effect::kDelay, "delay", 0.0),
                          v.drift(Effect::kTimeVaryingDelay, "delay"));
  const double gain = v.at(std::nullopt, "gain", 1.0);
  const double offset = v.at(Effect::kOffsetDrift, "offset", 0.0);
  const double drift = v.at(Effect::kOffsetDrift, "drift", 0.0);
  const std::span<const double> gain_c = v.drift(Effect::kTimeVaryingGain, "gain");
  const bool first = v.has(Effect::kFirstOrder), second = v.has(Effect::kSecondOrder);
  const bool play = v.has(Effect::kBacklash), saturate = v.has(Effect::kVelocitySaturation);
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
