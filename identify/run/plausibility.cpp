#include "identify/run/plausibility.h"

#include <algorithm>
#include <cmath>

#include "core/number_text.h"
#include "identify/run/sensors.h"
#include "identify/run/unexplained.h"

namespace rths::identify {
namespace {

// A standard error of 0 is none given (a held parameter): not a poor one.
bool poorly(const ParameterEstimate& p) {
  return p.std_error > 0.0 && p.std_error >= kPoorlyDetermined * std::abs(p.value);
}

const ParameterEstimate* named(const std::vector<ParameterEstimate>& parameters,
                               const std::string& name) {
  for (const auto& p : parameters)
    if (p.name == name) return &p;
  return nullptr;
}

bool is_drift(Effect effect) {
  return effect == Effect::kTimeVaryingStiffness || effect == Effect::kTimeVaryingGain ||
         effect == Effect::kTimeVaryingDelay;
}

// The yield (m) the fit put in the specimen, or nullopt for an effect without one.
std::optional<double> yield_displacement(Effect effect,
                                         const std::vector<ParameterEstimate>& parameters) {
  if (effect == Effect::kBoucWen)
    if (const auto* d = named(parameters, "yield_drift")) return std::abs(d->value);
  if (effect == Effect::kElastoPlastic) {
    const auto* force = named(parameters, "yield_force");
    const auto* stiffness = named(parameters, "plastic_stiffness");
    if (force && stiffness && stiffness->value > 0.0) return force->value / stiffness->value;
  }
  return std::nullopt;
}

// The largest |value| of `x`, 0 when empty.
double largest(const std::vector<double>& x) {
  double out = 0.0;
  for (double v : x) out = std::max(out, std::abs(v));
  return out;
}

// The energy a force does along the displacement over the record, sum F_j (x_j+1 - x_j-1) / 2
// (J for N and m): the area its loops enclose.
double loop_energy(const std::vector<double>& force, const std::vector<double>& x) {
  double out = 0.0;
  for (std::size_t j = 1; j + 1 < x.size() && j < force.size(); ++j)
    out += force[j] * 0.5 * (x[j + 1] - x[j - 1]);
  return out;
}

// "implausible: ..." where the force channel's elasto-plastic yield dissipates energy the record
// does not (plausibility.h); nullopt otherwise.
std::optional<std::string> no_yield_plateau(const ActuatorPath& path) {
  const ChannelSignals& s = identified_signals(path.id, Channel::kForce);
  const std::vector<double>& x = s.model_input.empty() ? s.input : s.model_input;
  const std::vector<double> with = prediction_without(path, Channel::kForce, {});
  const std::vector<double> without = prediction_without(path, Channel::kForce, {"elastoplastic"});
  const double rest = loop_energy(without, x);
  const double yield = loop_energy(with, x) - rest, measured = loop_energy(s.target, x) - rest;
  if (!(yield > 0.0) || measured >= kMinYieldDissipation * yield) return std::nullopt;
  return "implausible: its yield would dissipate " + core::format_number(yield) +
         " J over the record, the force read dissipates " + core::format_number(measured) +
         " J beyond the rest of the model: no yield plateau, the loops close (a stiffness that "
         "changed is no yield)";
}

}  // namespace

std::optional<std::string> implausible(Effect effect,
                                       const std::vector<ParameterEstimate>& parameters,
                                       double largest_displacement) {
  if (parameters.empty()) return std::nullopt;
  if (is_drift(effect)) {
    if (std::all_of(parameters.begin(), parameters.end(), poorly))
      return "poorly determined: every drift coefficient's standard error is at least " +
             core::format_number(kPoorlyDetermined) +
             " x its value, no change over the record the windows show";
  } else {
    for (const auto& p : parameters)
      if (poorly(p))
        return "poorly determined: " + p.describe() + ", its standard error at least " +
               core::format_number(kPoorlyDetermined) + " x its value";
  }
  if (const auto yield = yield_displacement(effect, parameters);
      yield && *yield >= kYieldBeyondReach * largest_displacement)
    return "implausible: a yield at " + core::format_number(*yield * 1e3) +
           " mm, beyond the largest displacement of the record (" +
           core::format_number(largest_displacement * 1e3) +
           " mm): no window shows the specimen yield";
  return std::nullopt;
}

void judge_plausible(ActuatorPath& path) {
  for (Channel channel : {Channel::kMeasured, Channel::kForce}) {
    if (!path.id.find(channel)) continue;
    const ChannelSignals& signals = identified_signals(path.id, channel);
    const double reach = largest(signals.model_input.empty() ? signals.input : signals.model_input);
    auto& named_effects =
        channel == Channel::kMeasured ? path.undeclared : path.specimen_undeclared;
    std::erase_if(named_effects, [&](const std::string& name) {
      Effect effect{};
      try {
        effect = parse_effect(name);
      } catch (const std::invalid_argument&) {
        return false;  // a changed value or a sensor's reading: no fitted magnitude of its own
      }
      const EffectEstimate* estimate = path.estimate(channel, effect);
      if (!estimate) return false;
      auto reason = implausible(effect, estimate->parameters, reach);
      if (!reason && effect == Effect::kElastoPlastic && channel == Channel::kForce)
        reason = no_yield_plateau(path);
      if (!reason) return false;
      path.rejected.push_back({channel, part_of(name, channel, path.actuator), name, 0.0, *reason});
      return true;
    });
  }
}

}  // namespace rths::identify
