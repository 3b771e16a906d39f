#include "identify/model/parameters.h"

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

// The specimen effects' parameters, scaled by the force and displacement they relate.
std::vector<ParamSpec> specimen_effect_params(Effect effect, const SignalScales& sc) {
  const double k_scale = sc.target / sc.input;
  switch (effect) {
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
    default: break;
  }
  throw std::logic_error("unhandled effect");
}

}  // namespace

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
    case Effect::kStrokeLimit:
      // Started at the measured peak: a rod that reached its end shows the end as its peak.
      return {param_spec("stroke", "m", sc.target_peak, 0.1 * sc.input, 1e300,
                         {sc.target_peak, 0.95 * sc.target_peak})};
    case Effect::kTimeVaryingDelay: return drift_params("delay", "s", 0.005, 0.1);
    case Effect::kTimeVaryingGain: return drift_params("gain", "-", 0.02, 0.5);
    case Effect::kStiffness:
    case Effect::kDamping:
    case Effect::kCoulomb:
    case Effect::kBoucWen:
    case Effect::kCubicStiffness:
    case Effect::kTimeVaryingStiffness:
    case Effect::kInertia:
    case Effect::kElastoPlastic: return specimen_effect_params(effect, sc);
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

}  // namespace rths::identify
