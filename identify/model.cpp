#include "identify/model.h"

#include "identify/evidence.h"

#include <numbers>
#include <algorithm>
#include <array>
#include <cmath>
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
    ParamSpec spec = param_spec(prefix + "_c" + std::to_string(k), unit, scale, -bound, bound, {0.0});
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
        edge > 0.0 ? std::max(kSpecimenInputCutoffFactor * signal_band(s.input, data.dt), edge) : 0.0;
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
      ParamSpec offset = param_spec("offset", measured ? "m" : "N", out_scale, -1e300, 1e300, {0.0});
      ParamSpec drift = param_spec("drift", measured ? "m" : "N", out_scale, -1e300, 1e300, {0.0});
      offset.record_specific = drift.record_specific = true;
      return {offset, drift};
    }
    case Effect::kFirstOrder:
      return {param_spec("time_constant", "s", 0.01, 0.2 * sc.dt, 1.0, {0.005, 0.03})};
    case Effect::kSecondOrder:
      return {param_spec("natural_frequency", "rad/s", 100.0, 2.0 * std::numbers::pi * 0.2, std::numbers::pi / sc.dt,
               {2.0 * std::numbers::pi * 5.0, 2.0 * std::numbers::pi * 20.0}),
              param_spec("damping_ratio", "-", 1.0, 0.05, 5.0, {0.7})};
    case Effect::kBacklash:
      return {non_negative(param_spec("width", "m", 0.05 * sc.input, 0.0, 10.0 * sc.input,
                            {0.03 * sc.input, 0.2 * sc.input}),
                           "a negative backlash width")};
    case Effect::kVelocitySaturation:
      return {param_spec("max_velocity", "m/s", sc.velocity, 0.01 * sc.velocity, 1e300,
               {0.8 * sc.velocity, 2.0 * sc.velocity})};
    case Effect::kTimeVaryingDelay:
      return drift_params("delay", "s", 0.005, 0.1);
    case Effect::kTimeVaryingGain:
      return drift_params("gain", "-", 0.02, 0.5);
    case Effect::kStiffness:
      return {non_negative(param_spec("stiffness", "N/m", k_scale, 0.0, 1e300, {0.0}),
                           "a negative stiffness")};
    case Effect::kDamping:
      return {non_negative(param_spec("damping", "N s/m", sc.target / sc.velocity, 0.0, 1e300, {0.0}),
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
      return {param_spec("cubic_stiffness", "N/m^3", sc.target / std::pow(sc.input, 3), -1e300, 1e300,
               {0.0})};
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
  return declared_specs(std::move(out), declarations);
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

ChannelModel declared_model(Channel channel, const std::vector<Effect>& effects,
                            const SignalScales& scales) {
  ChannelModel model;
  model.channel = channel;
  for (const auto& spec : base_params(channel, scales)) model.params.push_back(spec.guesses[0]);
  for (Effect e : effects) {
    if (model.has(e)) continue;
    std::vector<double> neutral;
    for (const auto& spec : effect_params(e, channel, scales)) {
      neutral.push_back(std::clamp(0.0, spec.lower, spec.upper));
    }
    // Dynamics with a zero time constant or a finite neutral frequency would not be neutral.
    if (e == Effect::kFirstOrder) neutral[0] = effect_params(e, channel, scales)[0].lower;
    if (e == Effect::kSecondOrder) {
      neutral = {effect_params(e, channel, scales)[0].upper * 0.5, 0.7};
    }
    if (e == Effect::kVelocitySaturation) neutral[0] = 1e3 * scales.velocity;
    if (e == Effect::kCoulomb || e == Effect::kBoucWen) {
      neutral[1] = effect_params(e, channel, scales)[1].guesses[0];
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

void predict(const ChannelModel& model, std::span<const double> p, const ChannelSignals& sig,
             std::vector<double>& out) {
  const std::size_t n = sig.size();
  out.assign(n, 0.0);
  if (n == 0) return;
  const double t_mid = 0.5 * (sig.time.front() + sig.time.back());
  const double duration = std::max(sig.time.back() - sig.time.front(), sig.dt);
  const auto norm_time = [&](std::size_t i) { return (sig.time[i] - t_mid) / duration; };

  // Unpack parameters by effect.
  double gain = 1.0, delay = 0.0, offset = 0.0, drift = 0.0;
  double time_constant = 0.0, wn = 0.0, zeta = 0.0, backlash = 0.0, vmax = 0.0;
  double k = 0.0, k3 = 0.0, c = 0.0, fc = 0.0, vc = 1.0, mass = 0.0;
  double f_bw = 0.0, d_y = 1.0, k_p = 0.0, f_y = 0.0;
  std::span<const double> delay_c, gain_c, k_c;
  bool first = false, second = false, play = false, saturate = false, bouc_wen = false;
  bool elasto_plastic = false;
  std::size_t i = 0;
  if (model.channel == Channel::kMeasured) gain = p[i++];
  for (Effect e : model.effects) {
    switch (e) {
      case Effect::kDelay: delay = p[i++]; break;
      case Effect::kOffsetDrift: offset = p[i++]; drift = p[i++]; break;
      case Effect::kFirstOrder: first = true; time_constant = p[i++]; break;
      case Effect::kSecondOrder: second = true; wn = p[i++]; zeta = p[i++]; break;
      case Effect::kBacklash: play = true; backlash = p[i++]; break;
      case Effect::kVelocitySaturation: saturate = true; vmax = p[i++]; break;
      case Effect::kTimeVaryingDelay: delay_c = p.subspan(i, kDriftTerms); i += kDriftTerms; break;
      case Effect::kTimeVaryingGain: gain_c = p.subspan(i, kDriftTerms); i += kDriftTerms; break;
      case Effect::kStiffness: k = p[i++]; break;
      case Effect::kDamping: c = p[i++]; break;
      case Effect::kCoulomb: fc = p[i++]; vc = p[i++]; break;
      case Effect::kBoucWen: bouc_wen = true; f_bw = p[i++]; d_y = p[i++]; break;
      case Effect::kCubicStiffness: k3 = p[i++]; break;
      case Effect::kTimeVaryingStiffness: k_c = p.subspan(i, kDriftTerms); i += kDriftTerms; break;
      case Effect::kInertia: mass = p[i++]; break;
      case Effect::kElastoPlastic: elasto_plastic = true; k_p = p[i++]; f_y = p[i++]; break;
    }
  }
  if (i != p.size()) throw std::invalid_argument("parameter count does not match the model");

  const bool shifted = delay != 0.0 || !delay_c.empty();
  const auto shifted_at = [&](std::span<const double> x, std::size_t j) {
    if (!shifted) return x[j];
    const double tau =
        std::max(0.0, delay + (delay_c.empty() ? 0.0 : drift_profile(delay_c, norm_time(j))));
    return interpolate(x, static_cast<double>(j) - tau / sig.dt);
  };

  if (model.channel == Channel::kMeasured) {
    const double decay = first ? std::exp(-sig.dt / std::max(time_constant, 1e-12)) : 0.0;
    // Tustin biquad of wn^2 / (s^2 + 2 zeta wn s + wn^2), pre-warp free (rates well below Nyquist).
    const double K = 2.0 / sig.dt;
    const double a0 = K * K + 2.0 * zeta * wn * K + wn * wn;
    const double b0 = wn * wn / a0, b1 = 2.0 * b0, b2 = b0;
    const double a1 = (2.0 * wn * wn - 2.0 * K * K) / a0;
    const double a2 = (K * K - 2.0 * zeta * wn * K + wn * wn) / a0;
    const double x0 = shifted_at(sig.input, 0);
    double y1 = x0;                  // first-order state
    double s1 = 0.0, s2 = 0.0;  // direct form II transposed states
    if (second) {
      // Direct form II transposed at rest with input x0 (DC gain 1): y = x0.
      s2 = b2 * x0 - a2 * x0;
      s1 = b1 * x0 - a1 * x0 + s2;
    }
    double play_out = x0, sat_out = x0;
    const double half_width = 0.5 * std::abs(backlash);
    const double max_step = std::abs(vmax) * sig.dt;
    for (std::size_t j = 0; j < n; ++j) {
      double x = shifted_at(sig.input, j);
      if (first) {
        y1 = decay * y1 + (1.0 - decay) * x;
        x = y1;
      }
      if (second) {
        const double y = b0 * x + s1;
        s1 = b1 * x - a1 * y + s2;
        s2 = b2 * x - a2 * y;
        x = y;
      }
      if (play) {
        play_out = std::clamp(play_out, x - half_width, x + half_width);
        x = play_out;
      }
      if (saturate) {
        sat_out += std::clamp(x - sat_out, -max_step, max_step);
        x = sat_out;
      }
      const double g = gain_c.empty() ? gain : gain * (1.0 + drift_profile(gain_c, norm_time(j)));
      out[j] = g * x + offset + drift * norm_time(j);
    }
    return;
  }

  // The specimen runs on the low-passed displacement when there is one (make_signals).
  const std::vector<double>& displacement = sig.model_input.empty() ? sig.input : sig.model_input;
  double z = 0.0, plastic = 0.0;
  double previous_d = shifted_at(displacement, 0);
  const double vc_safe = std::max(std::abs(vc), 1e-12);
  const double dy_safe = std::max(std::abs(d_y), 1e-12);
  for (std::size_t j = 0; j < n; ++j) {
    const double d = shifted_at(displacement, j);
    const double v = shifted_at(sig.velocity, j);
    const double s = norm_time(j);
    const double k_now = k_c.empty() ? k : k + drift_profile(k_c, s);
    double f = k_now * d + k3 * d * d * d + c * v + offset + drift * s;
    if (fc != 0.0) f += fc * std::tanh(v / vc_safe);
    if (mass != 0.0) f += mass * shifted_at(sig.acceleration, j);
    if (bouc_wen) {
      z = advance_bouc_wen(z, (d - previous_d) / dy_safe);
      f += f_bw * z;
    }
    if (elasto_plastic) {
      plastic = std::clamp(plastic + k_p * (d - previous_d), -std::abs(f_y), std::abs(f_y));
      f += plastic;
    }
    previous_d = d;
    out[j] = f;
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
