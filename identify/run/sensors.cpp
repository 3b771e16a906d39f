#include "identify/run/sensors.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <utility>
#include <vector>

#include "identify/fit/effect_parameters.h"
#include "identify/model/model.h"
#include "identify/model/study_config.h"

namespace rths::identify {
namespace {

// The median of a chi-square variable of one degree of freedom: (step / (sqrt 2 sigma))^2 for a
// white Gaussian noise's step.
constexpr double kMedianOfChiSquare1 = 0.45493642311957;

bool sensor_effect(const std::string& effect) {
  return effect == "offset_drift" || effect == "noise" || effect == "scale";
}

void remove(std::vector<std::string>& names, const std::string& name) {
  names.erase(std::remove(names.begin(), names.end(), name), names.end());
}

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// sigma (m or N) of `channel`'s noise (sensors.h): the white part of its final model's residual,
// from the median of its squared steps.
double channel_noise(const Identification& id, Channel channel) {
  const ChannelIdentification* c = id.find(channel);
  if (!c) return 0.0;
  const ChannelSignals& signals = identified_signals(id, channel);
  if (signals.size() < 2) return 0.0;
  const std::vector<double> prediction = predict(c->final_fit.model, signals);
  std::vector<double> residual(signals.size());
  for (std::size_t j = 0; j < signals.size(); ++j) residual[j] = signals.target[j] - prediction[j];
  return white_noise(residual);
}

void attribute_displacement_scale(ActuatorPath& path) {
  if (!has(path.undeclared, "gain error") || !(path.declared_stiffness > 0.0) ||
      !(path.declared_gain > 0.0) || !linear_specimen(path.id))
    return;
  const double scale = path.fitted_gain / path.declared_gain;
  if (std::abs(scale * path.fitted_stiffness / path.declared_stiffness - 1.0) > kScaleMatch) return;
  path.displacement_scale = scale;
  const ChannelIdentification* c = path.id.find(Channel::kMeasured);
  if (c && !c->final_fit.std_errors.empty())
    path.displacement_scale_error = c->final_fit.std_errors.front() / path.declared_gain;
  remove(path.undeclared, "gain error");
  path.undeclared.push_back("scale");
  remove(path.specimen_undeclared, "stiffness change");
}

// `model`'s named parameter times `factor`, where it has one.
void scale_param(ChannelModel& model, std::optional<Effect> effect, const std::string& name,
                 double factor, const SignalScales& scales) {
  if (const auto i = model.index_of(effect, name, scales)) model.params[*i] *= factor;
}

// The displacement sensor's offset drift as it shows on the force channel (sensors.h), in the
// force model's units {offset N, drift N per record}; {0, 0} unless both channels fitted one.
std::pair<double, double> displacement_offset_in_force(const ActuatorPath& path) {
  const ChannelIdentification* measured = path.id.find(Channel::kMeasured);
  const ChannelIdentification* force = path.id.find(Channel::kForce);
  if (!measured || !force || !measured->final_fit.model.has(Effect::kOffsetDrift) ||
      !force->final_fit.model.has(Effect::kOffsetDrift))
    return {0.0, 0.0};
  const SignalScales scales = signal_scales(identified_signals(path.id, Channel::kMeasured));
  const ChannelModel& m = measured->final_fit.model;
  // The force's term in the displacement itself: a hysteresis moves on its increments only.
  const double k = force->final_fit.model
                       .param(Effect::kStiffness, "stiffness",
                              signal_scales(identified_signals(path.id, Channel::kForce)))
                       .value_or(0.0);
  return {-k * m.param(Effect::kOffsetDrift, "offset", scales).value_or(0.0),
          -k * m.param(Effect::kOffsetDrift, "drift", scales).value_or(0.0)};
}

// The load cell's own offset drift {N, N per record}: the force channel's less the displacement
// sensor's share.
std::pair<double, double> load_cell_own_offset(const ActuatorPath& path) {
  const ChannelIdentification* force = path.id.find(Channel::kForce);
  if (!force) return {0.0, 0.0};
  const SignalScales scales = signal_scales(identified_signals(path.id, Channel::kForce));
  const ChannelModel& f = force->final_fit.model;
  const auto [offset, drift] = displacement_offset_in_force(path);
  return {f.param(Effect::kOffsetDrift, "offset", scales).value_or(0.0) - offset,
          f.param(Effect::kOffsetDrift, "drift", scales).value_or(0.0) - drift};
}

// A load cell offset drift that the displacement sensor's explains is not the load cell's.
void attribute_force_offset(ActuatorPath& path) {
  if (!has(path.undeclared, "offset_drift") || !has(path.specimen_undeclared, "offset_drift"))
    return;
  const double spread = signal_scales(identified_signals(path.id, Channel::kForce)).target;
  const auto [offset, drift] = load_cell_own_offset(path);
  if (std::abs(offset) < kOwnOffsetShare * spread && std::abs(drift) < kOwnOffsetShare * spread)
    remove(path.specimen_undeclared, "offset_drift");
}

}  // namespace

double white_noise(std::span<const double> residual) {
  if (residual.size() < 2) return 0.0;
  std::vector<double> squared_steps(residual.size() - 1);
  for (std::size_t j = 1; j < residual.size(); ++j) {
    const double step = residual[j] - residual[j - 1];
    squared_steps[j - 1] = step * step;
  }
  const auto middle = squared_steps.begin() + static_cast<std::ptrdiff_t>(squared_steps.size() / 2);
  std::nth_element(squared_steps.begin(), middle, squared_steps.end());
  return std::sqrt(*middle / (2.0 * kMedianOfChiSquare1));
}

bool noise_named(const Identification& id, Channel channel, double sigma, double declared) {
  return id.find(channel) && sigma > kNoiseShare * noise_spread(id, channel) &&
         sigma > kNoiseAboveDeclared * declared;
}

bool linear_specimen(const Identification& id) {
  const ChannelIdentification* c = id.find(Channel::kForce);
  if (!c) return false;
  for (Effect e : c->final_fit.model.effects)
    if (e != Effect::kStiffness && e != Effect::kDamping && e != Effect::kInertia &&
        e != Effect::kOffsetDrift && e != Effect::kDelay)
      return false;
  return true;
}

double noise_spread(const Identification& id, Channel channel) {
  return signal_scales(identified_signals(id, channel)).target;
}

std::string part_of(const std::string& effect, Channel channel, int actuator) {
  const bool sensor = sensor_effect(effect) || (channel == Channel::kForce && effect == "delay");
  const std::string n = std::to_string(actuator);
  if (channel == Channel::kMeasured) return (sensor ? "displacement sensor " : "actuator ") + n;
  return (sensor ? "load cell " : "specimen ") + n;
}

void judge_sensors(ActuatorPath& path) {
  path.displacement_noise = channel_noise(path.id, Channel::kMeasured);
  path.force_noise = channel_noise(path.id, Channel::kForce);
  if (noise_named(path.id, Channel::kMeasured, path.displacement_noise,
                  path.declared_displacement_noise))
    path.undeclared.push_back("noise");
  if (noise_named(path.id, Channel::kForce, path.force_noise, path.declared_force_noise))
    path.specimen_undeclared.push_back("noise");
  attribute_force_offset(path);
  attribute_displacement_scale(path);
}

double noise_std_error(const ActuatorPath& path, Channel channel, double sigma) {
  const ChannelIdentification* c = path.id.find(channel);
  const double n = c ? static_cast<double>(identified_signals(path.id, channel).size()) : 0.0;
  return n > 0.0 ? sigma * std::sqrt(2.0 / n) : 0.0;
}

ChannelModel without_named(const ChannelModel& model, const ActuatorPath& path,
                           const std::string& effect, const SignalScales& scales) {
  const auto set_back = [&](std::optional<Effect> e, const std::string& name, double declared) {
    ChannelModel out = model;
    if (const auto i = out.index_of(e, name, scales)) out.params[*i] = declared;
    return out;
  };
  if (effect == "gain error") return set_back(std::nullopt, "gain", path.declared_gain);
  if (effect == "delay change") return set_back(Effect::kDelay, "delay", path.declared_delay);
  if (effect == "stiffness change")
    return set_back(Effect::kStiffness, "stiffness", path.declared_stiffness);
  return without_effect(model, parse_effect(effect), scales);
}

namespace {

// `model` of `channel` without the effects the re-run rejected on it (a sensor's scale and noise
// are no terms of the model: rig_models reads the scale true).
void take_out_rejected(ChannelModel& model, const ActuatorPath& path, Channel channel) {
  const SignalScales scales = signal_scales(identified_signals(path.id, channel));
  for (const auto& r : path.rejected)
    if (r.channel == channel && r.effect != "scale" && r.effect != "noise")
      model = without_named(model, path, r.effect, scales);
}

}  // namespace

RigModels rig_models(const ActuatorPath& path) {
  const ChannelIdentification* c = path.id.find(Channel::kMeasured);
  if (!c)
    throw std::invalid_argument("actuator " + std::to_string(path.actuator) +
                                ": actuator path not identified");
  const double s = path.was_rejected(Channel::kMeasured, "scale") ? 1.0 : path.displacement_scale;
  RigModels out{std::nullopt, std::nullopt, s, {}};
  std::vector<std::string> contradicted = path.undeclared, re_run = path.specimen_undeclared;
  for (const auto& held : path.held_not_named)
    (held.channel == Channel::kMeasured ? contradicted : re_run).push_back(held.effect);
  remove(contradicted, "noise");
  if (!contradicted.empty() || !path.delay_by_direction.empty()) {
    out.actuator = c->final_fit.model;
    take_out_rejected(*out.actuator, path, Channel::kMeasured);
    if (s != 1.0)
      scale_param(*out.actuator, std::nullopt, "gain", 1.0 / s,
                  signal_scales(identified_signals(path.id, Channel::kMeasured)));
  }
  const ChannelIdentification* force = path.id.find(Channel::kForce);
  remove(re_run, "noise");
  if (!force || re_run.empty()) return out;
  out.specimen = force->final_fit.model;
  take_out_rejected(*out.specimen, path, Channel::kForce);
  const SignalScales scales = signal_scales(identified_signals(path.id, Channel::kForce));
  if (out.specimen->has(Effect::kOffsetDrift)) {
    const auto [offset, drift] = load_cell_own_offset(path);
    if (const auto i = out.specimen->index_of(Effect::kOffsetDrift, "offset", scales))
      out.specimen->params[*i] = offset;
    if (const auto i = out.specimen->index_of(Effect::kOffsetDrift, "drift", scales))
      out.specimen->params[*i] = drift;
  }
  if (s != 1.0) {
    scale_param(*out.specimen, Effect::kStiffness, "stiffness", s, scales);
    scale_param(*out.specimen, Effect::kDamping, "damping", s, scales);
    scale_param(*out.specimen, Effect::kInertia, "mass", s, scales);
    scale_param(*out.specimen, Effect::kCoulomb, "smoothing_velocity", 1.0 / s, scales);
  }
  if (!out.actuator)
    for (const auto& name : path.declared_specimen)
      if (held_by_force_stages(parse_effect(name)))
        out.held_by_declared.push_back(parse_effect(name));
  return out;
}

}  // namespace rths::identify
