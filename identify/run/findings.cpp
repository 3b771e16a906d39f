#include "identify/run/findings.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "identify/model/study_config.h"
#include "identify/residual/delay_growth.h"
#include "identify/run/moving_parameter.h"
#include "identify/run/sensors.h"
#include "identify/run/unexplained.h"

namespace rths::identify {
namespace {

std::string parameters_text(const std::vector<ParameterEstimate>& parameters) {
  std::string out;
  for (const auto& p : parameters) out += (out.empty() ? "" : ", ") + p.describe();
  return out;
}

std::string number(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

void add_link_findings(const std::vector<NetworkPath>& links, const std::string& clock,
                       std::vector<Finding>& out) {
  const std::string why =
      clock == "real_time"
          ? "a link's lag reaches the response only as the answers the loop used, which the "
            "re-run replays (the platform's share)"
          : "in lockstep a link's lag does not reach the response";
  for (const auto& link : links)
    for (const auto& e : link.effects) {
      Finding f;
      f.part = "link to node " + std::to_string(link.node_id);
      f.effect = e.name;
      f.magnitude = e.detail;
      f.heldout_before = e.heldout_before;
      f.heldout_after = e.heldout_after;
      f.heldout_unit = "s RMS";
      f.not_rerun = why;
      out.push_back(std::move(f));
    }
}

// An offset drift's parameters as the sensor_drift stage holds them (study_config.h
// drift_in_time): the offset at t = 0 of the run and the drift per second.
void in_run_time(const Identification& id, Channel channel,
                 std::vector<ParameterEstimate>& parameters) {
  if (parameters.size() != 2) return;
  const ChannelSignals& signals = identified_signals(id, channel);
  const RigRecord rig{signals.time.front(), signal_scales(signals).duration};
  ParameterEstimate& offset = parameters[0];
  ParameterEstimate& drift = parameters[1];
  const auto [at_zero, rate] = drift_in_time(offset.value, drift.value, rig);
  const double rate_error = drift.std_error / rig.duration;
  offset.value = at_zero;
  offset.std_error = std::hypot(offset.std_error, rate_error * (rig.start + 0.5 * rig.duration));
  drift.value = rate;
  drift.std_error = rate_error;
  drift.unit += "/s";
}

// The moving parameter of a time-varying effect (findings.h, moving_parameter.h) and the
// magnitude's words for it.
void describe_moving(const ActuatorPath& path, Channel channel, Finding& f) {
  const std::optional<MovingParameter> moving = moving_parameter(path, channel, f.effect);
  if (!moving) return;
  f.moving = moving->shape;
  f.moving_unit = moving->unit;
  const ShapeFit& m = *f.moving;
  f.magnitude += "; moving, " + shape_name(m.shape) + ": " + number(m.start) + " " + f.moving_unit +
                 " at the start, " + number(m.end) + " " + f.moving_unit + " at the end";
  if (m.shape == DriftShape::kStep) f.magnitude += ", the step at " + number(m.at) + " s";
  if (m.shape == DriftShape::kExponential) f.magnitude += ", time constant " + number(m.at) + " s";
  const auto& merged = path.merged_constants;
  if (std::find(merged.begin(), merged.end(), constant_change_of(f.effect)) != merged.end())
    f.magnitude += " (declared " + number(declared_constant(path, f.effect)) +
                   (f.moving_unit.empty() ? "" : " " + f.moving_unit) + ")";
}

// The finding of `effect` on `channel` of `path`: its parameters and the held-out error of the
// step that added it (the declared and the final model's for a changed value).
Finding channel_finding(const ActuatorPath& path, Channel channel, const std::string& part,
                        const std::string& effect) {
  Finding f;
  f.part = part;
  f.effect = effect;
  f.heldout_unit = "of the signal's std";
  const ChannelIdentification* c = path.id.find(channel);
  if (!c) return f;
  f.heldout_before = c->declared_fit.heldout_error;
  f.heldout_after = c->final_fit.heldout_error;
  // A changed value or a sensor's reading, not a library effect.
  if (effect.find(' ') != std::string::npos || effect == "noise" || effect == "scale") return f;
  const Effect kind = parse_effect(effect);
  if (const EffectEstimate* e = path.estimate(channel, kind)) f.parameters = e->parameters;
  f.magnitude = parameters_text(f.parameters);
  describe_moving(path, channel, f);
  for (const auto& step : c->steps)
    if (step.effect == kind) {
      f.heldout_before = step.before.heldout_error;
      f.heldout_after = step.after.heldout_error;
    }
  return f;
}

// A sensor's noise (sensors.h): its RMS beside the signal's and the declared; random, not re-run.
void describe_noise(const ActuatorPath& path, Channel channel, Finding& f) {
  const bool force = channel == Channel::kForce;
  const double sigma = force ? path.force_noise : path.displacement_noise;
  const double declared = force ? path.declared_force_noise : path.declared_displacement_noise;
  f.parameters = {{"rms", force ? "N" : "m", sigma, noise_std_error(path, channel, sigma)}};
  f.magnitude = parameters_text(f.parameters) + " (" +
                percent_text(sigma / noise_spread(path.id, channel)) +
                " of the signal's std; declared " +
                (force ? number(declared) + " N" : number(declared * 1e3) + " mm") + ")";
  f.heldout_before = f.heldout_after = 0.0;
  f.not_rerun = "random: no re-run replays its samples, its share stays unexplained";
}

void add_path_findings(const ActuatorPath& path, std::vector<Finding>& out) {
  for (const auto& effect : path.undeclared) {
    Finding f = channel_finding(path, Channel::kMeasured,
                                part_of(effect, Channel::kMeasured, path.actuator), effect);
    if (effect == "gain error")
      f.magnitude =
          "gain " + number(path.fitted_gain) + " (declared " + number(path.declared_gain) + ")";
    if (effect == "delay change")
      f.magnitude = number(path.declared_delay * 1e3) + " -> " + number(path.fitted_delay * 1e3) +
                    " ms (declared -> fitted)";
    if (effect == "noise") describe_noise(path, Channel::kMeasured, f);
    if (effect == "scale") {
      f.parameters = {{"scale", "-", path.displacement_scale, path.displacement_scale_error}};
      f.magnitude = parameters_text(f.parameters) + " (the actuator's gain " +
                    number(path.fitted_gain) + " and the specimen's stiffness " +
                    number(path.fitted_stiffness) + " N/m as read; their product is as declared)";
      f.heldout_before = f.heldout_after = 0.0;  // the fit's own gain: no added effect's
    }
    out.push_back(std::move(f));
  }
  for (const auto& effect : path.specimen_undeclared) {
    Finding f = channel_finding(path, Channel::kForce,
                                part_of(effect, Channel::kForce, path.actuator), effect);
    if (effect == "stiffness change")
      f.magnitude =
          "stiffness " + number(path.fitted_stiffness) + " N/m (declared " +
          number(path.declared_stiffness) + " N/m" +
          (linear_specimen(path.id) ? "; a load cell reading " +
                                          number(path.fitted_stiffness / path.declared_stiffness) +
                                          " x the truth reads the same)"
                                    : ")");
    if (effect == "noise") describe_noise(path, Channel::kForce, f);
    out.push_back(std::move(f));
  }
}

// The platform's late answers, replayed in the re-run (run_residual.h links: "platform").
void add_platform_finding(const RunResidual* residual, std::vector<Finding>& out) {
  if (!residual) return;
  for (const auto& s : residual->links) {
    if (s.link != "platform") continue;
    Finding f;
    f.part = "platform";
    f.effect = s.effect;
    f.magnitude = residual->platform;
    f.response_removed = s.removed;
    f.response_share = s.share;
    out.push_back(std::move(f));
  }
}

// Each finding's part of the re-run (run_residual.h effects), or why it has none.
void add_response(const RunResidual* residual, std::vector<Finding>& findings) {
  for (Finding& f : findings) {
    if (!f.not_rerun.empty()) continue;
    if (!residual) {
      f.not_rerun = "the response was not re-run (the actuator channel was not identified)";
      continue;
    }
    f.not_rerun = "the study cannot hold it (see the re-run's notes)";
    for (const auto& note : residual->notes)
      if (note.rfind(f.part + ": " + f.effect + ": ", 0) == 0)
        f.not_rerun =
            "the study cannot hold it: " + note.substr(f.part.size() + 2 + f.effect.size() + 2);
    for (const auto& s : residual->effects)
      if (s.link == f.part && s.effect == f.effect) {
        f.response_removed = s.removed;
        f.response_share = s.share;
        f.not_rerun.clear();
      }
  }
}

// {shape, start, end, at_s (null for a line), unit} or null.
nlohmann::json moving_json(const Finding& f) {
  if (!f.moving) return nullptr;
  return {{"shape", shape_name(f.moving->shape)},
          {"start", f.moving->start},
          {"end", f.moving->end},
          {"at_s", f.moving->shape == DriftShape::kLinear ? nlohmann::json()
                                                          : nlohmann::json(f.moving->at)},
          {"unit", f.moving_unit}};
}

// A load cell whose lag grows over the run by at least its own mean (delay_growth.h on what the
// force channel's model, holding that mean, leaves): the channel's time base drifts against the
// loop's (a clock of its own), so its `delay` finding is named time_varying_delay, with the lag at
// the start and at the end of the run; the re-run holds the mean lag as before.
void name_time_base_drift(const ActuatorPath& path, std::vector<Finding>& findings) {
  const std::string part = part_of("delay", Channel::kForce, path.actuator);
  for (Finding& f : findings) {
    if (f.part != part || f.effect != "delay" || f.parameters.empty()) continue;
    const double mean = f.parameters.front().value;  // s
    const ChannelSignals& s = identified_signals(path.id, Channel::kForce);
    const std::vector<double> p =
        prediction_without(path, Channel::kForce, not_named_on(path, Channel::kForce));
    const auto g = delay_growth(s.time, minus(s.target, p), p, s.dt);
    const double duration = s.time.back() - s.time.front();
    if (!g || std::abs(g->growth) * duration < std::abs(mean)) continue;
    const double start = mean + g->mean_miss - 0.5 * g->growth * duration;
    const double end = start + g->growth * duration;
    f.effect = "time_varying_delay";
    f.magnitude = "lag " + number(start * 1e3) + " ms at the start -> " + number(end * 1e3) +
                  " ms at the end (" + number(g->growth * 1e6) +
                  " ppm: the channel's time base drifts against the loop's; a constant " +
                  number(mean * 1e3) + " ms fitted, held in the re-run)";
  }
}

}  // namespace

void estimate_effects(ActuatorPath& path) {
  path.estimates.clear();
  for (const auto& c : path.id.channels) {
    const SignalScales scales = signal_scales(identified_signals(path.id, c.channel));
    const auto add = [&](Effect effect, bool added, std::optional<double> share) {
      if (path.estimate(c.channel, effect)) return;
      EffectEstimate e{c.channel, effect, added, share,
                       effect_parameters(c.final_fit, effect, scales)};
      if (effect == Effect::kOffsetDrift) in_run_time(path.id, c.channel, e.parameters);
      path.estimates.push_back(std::move(e));
    };
    const auto declared = [&](Effect e) {
      return std::find(c.declared.begin(), c.declared.end(), e) != c.declared.end();
    };
    for (const auto& step : c.steps) add(step.effect, true, step.own_share);
    for (Effect effect : c.final_fit.model.effects)
      if (!declared(effect)) add(effect, true, std::nullopt);
    for (Effect effect : c.final_fit.model.effects) add(effect, false, std::nullopt);
  }
}

std::vector<Finding> collect_findings(const std::vector<NetworkPath>& links,
                                      const std::vector<ActuatorPath>& actuators,
                                      const RunResidual* residual, const std::string& clock) {
  std::vector<Finding> out;
  add_link_findings(links, clock, out);
  for (const auto& path : actuators) add_path_findings(path, out);
  add_response(residual, out);
  for (const auto& path : actuators) name_time_base_drift(path, out);
  std::vector<Finding> platform;
  add_platform_finding(residual, platform);
  out.insert(out.begin(), platform.begin(), platform.end());
  return out;
}

void describe_direction_delays(std::vector<ActuatorPath>& actuators,
                               std::vector<Unexplained>& unexplained,
                               std::vector<Finding>& findings, RunResidual* residual) {
  for (ActuatorPath& path : actuators) {
    const double change = path.fitted_delay - path.declared_delay;  // s
    const std::string part = part_of("delay change", Channel::kMeasured, path.actuator);
    const auto finding = std::find_if(findings.begin(), findings.end(), [&](const Finding& f) {
      return f.part == part && f.effect == "delay change";
    });
    if (finding == findings.end()) continue;
    for (Unexplained& u : unexplained) {
      const auto& direction = u.description.direction;
      if (u.actuator != path.actuator || u.channel != Channel::kMeasured || !direction ||
          !direction->of_rate ||
          std::abs(direction->lead_difference) < kSplitDelayShare * std::abs(change))
        continue;
      // A lead larger rising is a delay shorter rising.
      const double rising = path.fitted_delay - 0.5 * direction->lead_difference;
      const double falling = path.fitted_delay + 0.5 * direction->lead_difference;
      path.delay_by_direction =
          "a delay that differs by the direction of motion: about " + number(rising * 1e3) +
          " ms rising, " + number(falling * 1e3) + " ms falling (declared " +
          number(path.declared_delay * 1e3) + " ms; the re-run holds their mean " +
          number(path.fitted_delay * 1e3) + " ms), not one delay that changed";
      u.notes.push_back(path.delay_by_direction);
      findings.erase(finding);
      std::erase(path.undeclared, std::string("delay change"));
      path.not_named.push_back({Channel::kMeasured, "delay change"});
      if (residual)
        for (ResidualShare& s : residual->effects)
          if (s.link == part && s.effect == "delay change") s.effect = kDelaysByDirection;
      break;
    }
  }
}

std::string findings_text(const std::vector<Finding>& findings, const RunResidual* residual) {
  std::ostringstream out;
  out << "undeclared effects, every part:" << (findings.empty() ? " none" : "") << "\n";
  for (const Finding& f : findings) {
    out << "  " << f.part << ": " << f.effect;
    if (!f.magnitude.empty()) out << ": " << f.magnitude;
    const bool seconds = f.heldout_unit == "s RMS";
    if (f.heldout_before > 0.0)
      out << "; held-out "
          << (seconds ? number(f.heldout_before * 1e3) + " ms" : percent_text(f.heldout_before))
          << " -> "
          << (seconds ? number(f.heldout_after * 1e3) + " ms" : percent_text(f.heldout_after));
    if (f.response_removed)
      out << "; re-run: removes " << percent_text(*f.response_removed)
          << " of the worst floor's NRMSE (share " << percent_text(f.response_share) << ")";
    else
      out << "; not re-run: " << f.not_rerun;
    out << "\n";
  }
  if (residual)
    out << "unexplained after the re-run: " << percent_text(residual->identified)
        << " NRMSE on the worst floor (declared model: " << percent_text(residual->declared)
        << ")\n";
  return out.str();
}

nlohmann::json parameters_json(const std::vector<ParameterEstimate>& parameters) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : parameters)
    out.push_back(
        {{"name", p.name}, {"value", p.value}, {"std_error", p.std_error}, {"unit", p.unit}});
  return out;
}

nlohmann::json findings_json(const std::vector<Finding>& findings) {
  nlohmann::json out = nlohmann::json::array();
  for (const Finding& f : findings) {
    out.push_back(
        {{"part", f.part},
         {"effect", f.effect},
         {"magnitude", f.magnitude},
         {"parameters", parameters_json(f.parameters)},
         {"heldout_before", f.heldout_before},
         {"heldout_after", f.heldout_after},
         {"heldout_unit", f.heldout_unit},
         {"rerun", f.not_rerun.empty()},
         {"nrmse_removed",
          f.response_removed ? nlohmann::json(*f.response_removed) : nlohmann::json()},
         {"share", f.response_removed ? nlohmann::json(f.response_share) : nlohmann::json()},
         {"not_rerun", f.not_rerun},
         {"moving", moving_json(f)}});
  }
  return out;
}

}  // namespace rths::identify
