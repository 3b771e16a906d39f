#include "identify/run/unexplained.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "identify/fit/effect_parameters.h"
#include "identify/model/model.h"
#include "identify/run/sensors.h"

namespace rths::identify {
namespace {

ResidualDescription describe_channel(const ActuatorPath& path, Channel channel,
                                     const std::vector<std::string>& out) {
  const ChannelSignals& s = identified_signals(path.id, channel);
  const std::vector<double> p = prediction_without(path, channel, out);
  return describe_residual(s.time, minus(s.target, p), p, s.dt);
}

// Whether the effect is one the description may stand in for: a fitted form, not a sensor's
// reading judged elsewhere (noise, scale) or the delay the case declared.
bool judged(const std::string& effect, const ActuatorPath& path) {
  if (effect == "noise" || effect == "scale" || effect == "delay change") return false;
  if (effect == "stiffness change") return linear_specimen(path.id);
  return true;
}

// The identified model's held-out RMS error on the description's held-out windows.
double final_heldout_rms(const ActuatorPath& path, Channel channel,
                         const std::vector<std::string>& out) {
  const ChannelSignals& s = identified_signals(path.id, channel);
  return heldout_rms(minus(s.target, prediction_without(path, channel, out)));
}

void take_out(ActuatorPath& path, Channel channel, const std::string& effect) {
  auto& list = channel == Channel::kMeasured ? path.undeclared : path.specimen_undeclared;
  list.erase(std::remove(list.begin(), list.end(), effect), list.end());
  std::erase_if(path.estimates, [&](const EffectEstimate& e) {
    return e.channel == channel && effect_name(e.effect) == effect;
  });
  path.not_named.push_back({channel, effect});
}

// The RMS (about the mean) of `r`, and of what one step of its level leaves (the step at the
// sample that leaves least, at least kStepEdge of the record from either end).
std::pair<double, double> rms_and_after_one_step(std::span<const double> r) {
  const std::size_t n = r.size(), edge = std::max<std::size_t>(1, n / kStepEdge);
  double total = 0.0, squares = 0.0;
  for (double x : r) {
    total += x;
    squares += x * x;
  }
  const auto count = static_cast<double>(n);
  double best = squares - total * total / count, before = 0.0;
  const double spread = best;
  for (std::size_t k = 1; k < n; ++k) {
    before += r[k - 1];
    if (k < edge || n - k < edge) continue;
    const auto a = static_cast<double>(k), b = count - a;
    best = std::min(best, squares - before * before / a - (total - before) * (total - before) / b);
  }
  return {std::sqrt(std::max(0.0, spread) / count), std::sqrt(std::max(0.0, best) / count)};
}

// Whether one step of the offset explains the channel without `effect` (an offset drift) better
// than the drift does: what the step leaves below kDescriptionWins x what the drift leaves.
bool a_step_beats_the_drift(const ActuatorPath& path, Channel channel,
                            const std::vector<std::string>& kept,
                            const std::vector<std::string>& without) {
  const ChannelSignals& s = identified_signals(path.id, channel);
  const double with_drift =
      rms_and_after_one_step(minus(s.target, prediction_without(path, channel, kept))).first;
  const double stepped =
      rms_and_after_one_step(minus(s.target, prediction_without(path, channel, without))).second;
  return stepped < kDescriptionWins * with_drift;
}

// Whether the named stroke limit holds the reading where it acts: over the samples where the
// model with it and without it differ, what it leaves is below kFlatShare of what the model
// without it leaves there (a rod at its end reads flat; a reading rounded at its largest
// strokes is no end stop, however well a clip at its peak fits elsewhere).
bool the_limit_holds_the_reading(const ActuatorPath& path, Channel channel,
                                 const std::vector<std::string>& kept,
                                 const std::vector<std::string>& without) {
  const ChannelSignals& s = identified_signals(path.id, channel);
  const std::vector<double> with_it = prediction_without(path, channel, kept),
                            without_it = prediction_without(path, channel, without);
  const double scale = signal_scales(s).target;
  double left = 0.0, before = 0.0;
  for (std::size_t j = 0; j < s.size(); ++j) {
    if (!(std::abs(with_it[j] - without_it[j]) > 1e-9 * scale)) continue;
    left += (s.target[j] - with_it[j]) * (s.target[j] - with_it[j]);
    before += (s.target[j] - without_it[j]) * (s.target[j] - without_it[j]);
  }
  return before > 0.0 && left < kFlatShare * kFlatShare * before;
}

// The coefficient of the effect's term e = with - without that the residual without it,
// r = target - without, holds over the samples with |e| below its median and above it.
std::pair<double, double> coefficient_by_size(std::span<const double> target,
                                              std::span<const double> with,
                                              std::span<const double> without) {
  std::vector<double> size(target.size());
  for (std::size_t j = 0; j < size.size(); ++j) size[j] = std::abs(with[j] - without[j]);
  std::vector<double> sorted = size;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const double median = sorted[sorted.size() / 2];
  double re_low = 0.0, ee_low = 0.0, re_high = 0.0, ee_high = 0.0;
  for (std::size_t j = 0; j < size.size(); ++j) {
    const double e = with[j] - without[j], r = target[j] - without[j];
    (size[j] <= median ? re_low : re_high) += r * e;
    (size[j] <= median ? ee_low : ee_high) += e * e;
  }
  return {ee_low > 0.0 ? re_low / ee_low : 0.0, ee_high > 0.0 ? re_high / ee_high : 0.0};
}

// Where the record shows `effect`'s term is not proportional to its signal (unexplained.h): the
// words that say so, with its coefficient over the smaller and the larger half of the term;
// empty where it is proportional or `effect` is no such term.
std::string not_proportional(const ActuatorPath& path, Channel channel, const std::string& effect,
                             const std::vector<std::string>& kept,
                             const std::vector<std::string>& without) {
  if (effect != "damping" && effect != "inertia" && effect != "cubic_stiffness") return "";
  const EffectEstimate* estimate = path.estimate(channel, parse_effect(effect));
  if (!estimate || estimate->parameters.empty()) return "";
  const ChannelSignals& s = identified_signals(path.id, channel);
  const auto [low, high] = coefficient_by_size(s.target, prediction_without(path, channel, kept),
                                               prediction_without(path, channel, without));
  if (!(std::abs(high - low) > kProportionalSpread * std::max(std::abs(low), std::abs(high))))
    return "";
  const ParameterEstimate& p = estimate->parameters.front();
  return effect + " not named: its form is not what the record shows (" + p.name + " " +
         number_text(low * p.value) + " " + p.unit + " over the smaller half of its term, " +
         number_text(high * p.value) + " " + p.unit + " over the larger)";
}

void judge_channel(ActuatorPath& path, Channel channel) {
  if (!path.id.find(channel)) return;
  const std::vector<std::string> named =
      channel == Channel::kMeasured ? path.undeclared : path.specimen_undeclared;
  for (const auto& effect : named) {
    if (!judged(effect, path)) continue;
    const std::vector<std::string> kept = not_named_on(path, channel);
    std::vector<std::string> without = kept;
    without.push_back(effect);
    if ((effect == "offset_drift" && a_step_beats_the_drift(path, channel, kept, without)) ||
        (effect == "stroke_limit" && !the_limit_holds_the_reading(path, channel, kept, without))) {
      take_out(path, channel, effect);
      continue;
    }
    const ResidualDescription d = describe_channel(path, channel, without);
    if (d.any() && d.heldout_rms < kDescriptionWins * final_heldout_rms(path, channel, kept)) {
      take_out(path, channel, effect);
      continue;
    }
    const std::string why = not_proportional(path, channel, effect, kept, without);
    if (why.empty()) continue;
    if (effect == "cubic_stiffness") {  // no study's stage holds it: described only
      take_out(path, channel, effect);
      continue;
    }
    auto& list = channel == Channel::kMeasured ? path.undeclared : path.specimen_undeclared;
    std::erase(list, effect);
    path.held_not_named.push_back(
        {channel, effect, why + "; the re-run holds the fitted one, the nearest form it has"});
  }
}

std::string channel_part(const ResidualDescription& d, Channel channel, int actuator) {
  const std::string n = std::to_string(actuator);
  if (channel == Channel::kMeasured) return "actuator " + n;
  const double periodic = d.periodic ? d.periodic->explained : 0.0;
  const double others = std::max({d.amplitude ? d.amplitude->explained : 0.0,
                                  d.direction ? d.direction->explained : 0.0,
                                  d.time_varying ? d.time_varying->explained : 0.0});
  return (periodic >= others ? "load cell " : "specimen ") + n;
}

// A force that falls against the model in one step from some time on: the specimen lost capacity.
bool capacity_drop(const Unexplained& u) {
  const auto& trend = u.description.time_varying;
  return trend && !trend->of_rate && u.channel == Channel::kForce &&
         trend->shape.shape == DriftShape::kStep && trend->shape.end < trend->shape.start;
}

std::vector<std::string> kinds_of(const Unexplained& u) {
  std::vector<std::string> out = u.description.kinds();
  if (capacity_drop(u)) out.push_back("capacity_drop");
  return out;
}

// "+8 ms", "-0.3 ms": a change of the measured's lead on the model (s), in ms.
std::string lead_text(double seconds) {
  std::string out = number_text(1e3 * seconds) + " ms";
  if (seconds >= 0.0) out.insert(out.begin(), '+');
  return out;
}

std::string signature_text(const Unexplained& u) {
  const ResidualDescription& d = u.description;
  std::vector<std::string> parts;
  if (d.periodic)
    parts.push_back("periodic at " + fixed_text(d.periodic->frequency, 2) + " Hz, " +
                    number_text(d.periodic->amplitude) + " " + u.unit);
  if (d.amplitude && d.amplitude->of_rate)
    parts.push_back("a function of the rate's amplitude: the measured's lead on the model " +
                    lead_text(d.amplitude->lead_change) + " from the median rate to " +
                    number_text(d.amplitude->at_input) + " " + u.unit + "/s");
  else if (d.amplitude)
    parts.push_back("a function of the input's amplitude: measured / model " +
                    number_text(d.amplitude->ratio_change_pct) + " % from the median to " +
                    number_text(d.amplitude->at_input) + " " + u.unit);
  if (d.direction && d.direction->of_rate) {
    parts.push_back("a function of the direction of motion: the measured's lead on the model " +
                    lead_text(d.direction->lead_difference) + " rising against falling");
  } else if (d.direction) {
    std::string text = "a function of the input's direction: positive side " +
                       number_text(d.direction->asymmetry_pct) + " % against the negative";
    if (d.direction->hysteresis_width > 0.0)
      text += ", loading and unloading apart by " + number_text(d.direction->hysteresis_width) +
              " " + u.unit + " RMS";
    parts.push_back(text);
  }
  if (d.time_varying && d.time_varying->of_rate) {
    const ShapeFit& shape = d.time_varying->shape;
    std::string text = "the measured's lead on the model changes over the record, " +
                       shape_name(shape.shape) + ": " + lead_text(shape.start) + " at the start, " +
                       lead_text(shape.end) + " at the end";
    if (shape.shape == DriftShape::kStep) text += ", the step at " + fixed_text(shape.at, 2) + " s";
    if (shape.shape == DriftShape::kExponential)
      text += ", time constant " + number_text(shape.at) + " s";
    parts.push_back(text);
  } else if (d.time_varying) {
    const ShapeFit& shape = d.time_varying->shape;
    std::string text = "changes over the record, " + shape_name(shape.shape) +
                       ": measured / model " + number_text(100.0 * shape.start) +
                       " % at the start, " + number_text(100.0 * shape.end) + " % at the end";
    if (shape.shape == DriftShape::kStep) text += ", the step at " + fixed_text(shape.at, 2) + " s";
    if (shape.shape == DriftShape::kExponential)
      text += ", time constant " + number_text(shape.at) + " s";
    parts.push_back(text + (capacity_drop(u) ? " (a capacity drop)" : ""));
  }
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : "; ") + p;
  return out + " (explains " + number_text(100.0 * d.explained) + " % of the residual held out)";
}

nlohmann::json trend_json(const TrendSignature& t) {
  return {{"explained_pct", 100.0 * t.explained},
          {"change_pct", t.change_pct},
          {"of_rate", t.of_rate},
          {"shape", shape_name(t.shape.shape)},
          {"start_pct", t.of_rate ? nlohmann::json() : nlohmann::json(100.0 * t.shape.start)},
          {"end_pct", t.of_rate ? nlohmann::json() : nlohmann::json(100.0 * t.shape.end)},
          {"start_lead_s", t.of_rate ? nlohmann::json(t.shape.start) : nlohmann::json()},
          {"end_lead_s", t.of_rate ? nlohmann::json(t.shape.end) : nlohmann::json()},
          {"at_s",
           t.shape.shape == DriftShape::kLinear ? nlohmann::json() : nlohmann::json(t.shape.at)}};
}

nlohmann::json or_null(bool present, nlohmann::json value) {
  return present ? value : nlohmann::json();
}

}  // namespace

std::string number_text(double value, int digits) {
  std::ostringstream out;
  out.precision(digits);
  out << value;
  return out.str();
}

std::string fixed_text(double value, int decimals) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << value;
  return out.str();
}

std::vector<double> prediction_without(const ActuatorPath& path, Channel channel,
                                       const std::vector<std::string>& effects) {
  const ChannelIdentification* c = path.id.find(channel);
  const ChannelSignals& signals = identified_signals(path.id, channel);
  if (effects.empty() && c->final_fit.prediction.size() == signals.size())
    return c->final_fit.prediction;
  const SignalScales scales = signal_scales(signals);
  ChannelModel model = c->final_fit.model;
  for (const auto& effect : effects) model = without_named(model, path, effect, scales);
  return predict(model, signals);
}

std::vector<std::string> not_named_on(const ActuatorPath& path, Channel channel) {
  std::vector<std::string> out;
  for (const auto& n : path.not_named)
    if (n.channel == channel) out.push_back(n.effect);
  return out;
}

void judge_named(ActuatorPath& path) {
  judge_channel(path, Channel::kMeasured);
  judge_channel(path, Channel::kForce);
}

std::vector<Unexplained> describe_unexplained(const ActuatorPath& path) {
  std::vector<Unexplained> out;
  for (Channel channel : {Channel::kMeasured, Channel::kForce}) {
    if (!path.id.find(channel)) continue;
    ResidualDescription d = describe_channel(path, channel, not_named_on(path, channel));
    const ChannelSignals& s = identified_signals(path.id, channel);
    if (!d.any() || d.described_rms < kMinSignalShare * signal_scales(s).target) continue;
    const bool force = channel == Channel::kForce;
    Unexplained u;
    u.actuator = path.actuator;
    u.channel = channel;
    u.part = channel_part(d, channel, path.actuator);
    u.channel_word = force ? "force" : "displacement";
    u.unit = force ? "N" : "m";
    u.description = std::move(d);
    u.time = s.time;
    for (const auto& held : path.held_not_named)
      if (held.channel == channel) u.notes.push_back(held.why);
    out.push_back(std::move(u));
  }
  return out;
}

std::string Unexplained::text() const {
  std::string out = "unexplained on " + part + " (" + channel_word + "): " + signature_text(*this);
  for (const std::string& note : notes) out += "; " + note;
  // Without a re-run (the actuator channel not identified) there is no response error to share.
  return out + (share ? std::string("; share ") + fixed_text(100.0 * *share, 0) + " %"
                      : "; not re-run, no share");
}

nlohmann::json Unexplained::json() const {
  const ResidualDescription& d = description;
  const auto pct = [](double ratio) { return 100.0 * ratio; };
  return {
      {"part", part},
      {"channel", channel_word},
      {"notes", notes},
      {"share_pct", share ? nlohmann::json(pct(*share)) : nlohmann::json()},
      {"kinds", kinds_of(*this)},
      {"periodic",
       or_null(d.periodic.has_value(),
               d.periodic ? nlohmann::json{{"frequency_hz", d.periodic->frequency},
                                           {"amplitude", d.periodic->amplitude},
                                           {"unit", unit},
                                           {"explained_pct", pct(d.periodic->explained)}}
                          : nlohmann::json())},
      {"amplitude",
       or_null(d.amplitude.has_value(),
               d.amplitude ? nlohmann::json{{"explained_pct", pct(d.amplitude->explained)},
                                            {"ratio_change_pct", d.amplitude->ratio_change_pct},
                                            {"at_input", d.amplitude->at_input},
                                            {"of_rate", d.amplitude->of_rate},
                                            {"lead_change_s", d.amplitude->lead_change},
                                            {"unit", unit}}
                           : nlohmann::json())},
      {"direction",
       or_null(d.direction.has_value(),
               d.direction ? nlohmann::json{{"explained_pct", pct(d.direction->explained)},
                                            {"asymmetry", d.direction->asymmetry_pct},
                                            {"of_rate", d.direction->of_rate},
                                            {"lead_difference_s", d.direction->lead_difference},

                                            {"hysteresis_width", d.direction->hysteresis_width},
                                            {"unit", unit}}
                           : nlohmann::json())},
      {"time_varying", or_null(d.time_varying.has_value(),
                               d.time_varying ? trend_json(*d.time_varying) : nlohmann::json())},
      {"explained_pct", pct(d.explained)},
      {"residual_rms", d.residual_rms},
      {"unit", unit},
      {"text", text()}};
}

void judge_noise_beside(ActuatorPath& path, const std::vector<Unexplained>& described) {
  for (Channel channel : {Channel::kMeasured, Channel::kForce}) {
    if (!path.id.find(channel)) continue;
    const ChannelSignals& s = identified_signals(path.id, channel);
    // What every description of the channel leaves (a trend's and a hum's alike).
    std::vector<double> left =
        minus(s.target, prediction_without(path, channel, not_named_on(path, channel)));
    bool any = false;
    for (const Unexplained& u : described) {
      if (u.actuator != path.actuator || u.channel != channel) continue;
      left = minus(left, u.description.described);
      any = true;
    }
    if (!any) continue;
    const bool force = channel == Channel::kForce;
    double& sigma = force ? path.force_noise : path.displacement_noise;
    sigma = white_noise(left);
    if (noise_named(path.id, channel, sigma,
                    force ? path.declared_force_noise : path.declared_displacement_noise))
      continue;
    auto& list = force ? path.specimen_undeclared : path.undeclared;
    list.erase(std::remove(list.begin(), list.end(), "noise"), list.end());
  }
}

}  // namespace rths::identify
