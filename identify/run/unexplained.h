#pragma once
// What the identified model of a run's channel leaves, described without presuming an effect:
// a residual outside the library is located and described, not forced into a name.
//
// Input: one actuator path (actuator_path.h) after its channels were identified and judged
// (judge_specimen, judge_sensors, estimate_effects). Per channel c (measured: command -> the
// displacement read, m; force: displacement read -> the load cell's force, N) with target y_j, the
// identified model's prediction p_j (the final fit's) and the residual r_j = y_j - p_j:
//   each channel's residual described (identify/residual/description.h: a static map over the
//   model's output, its amplitude and direction, a trend of the measured / model ratio over the
//   record with its shape, a spectral peak), each test counting only when it explains
//   kMinExplained of the residual held out.
// A channel is reported only when what the accepted tests describe together has an RMS (about its
// mean) of at least kMinSignalShare of the channel's target std (a clean record, sensor noise and
// 16-bit converters, leaves noise no test explains). Its part: the force channel's is "load cell
// N" when its periodic part holds most of the description (a ripple the load cell reads), else
// "specimen N"; the measured channel's is "actuator N". A force channel whose trend is a step
// down is a capacity drop (its kinds add "capacity_drop").
//
// Named only where the fit beats the description (judge_named): for every effect named on a
// channel (a search step, "gain error", "stiffness change"), the model without it (the step's
// effect taken out, the gain or stiffness set back to the declared) is described as above on the
// train windows; where the description's held-out RMS error is below kDescriptionWins x the
// identified model's, the description wins: the effect is not named (taken out of the path's
// lists and estimates: no magnitude anywhere) and the channel is described against the model
// without it.
//
// An offset drift is not named where one step of the channel's offset, at the moment that leaves
// least (at least 1 / kStepEdge of the record from either end), leaves below kDescriptionWins x
// the RMS the drift leaves: an offset that changed at one moment (a joint that slipped, a zero
// that jumped) is no drift, and the events search locates it in time (residual_floor.h).
//
// A term proportional to one signal (damping: the rate, inertia: the acceleration,
// cubic_stiffness: the displacement cubed; its part of the model e_j = p_j - p_j without it) is
// named only where the record shows that form: the coefficient a of e that the residual without
// the effect holds, r_j = a e_j by least squares, over the samples with |e_j| below its median
// and over those above it, differs by at most kProportionalSpread of the larger (a damper in
// v |v| holds a coefficient at its large rates several times the one at its small rates). Where
// it differs more the effect is not named: a term a study's stage holds (damping, inertia) stays
// in the re-run as the nearest form it has and is said beside the channel's description
// (ActuatorPath::held_not_named); one that none holds (cubic_stiffness) is taken out as above.
//
// A stroke limit is not named where, over the samples it acts on, it leaves kFlatShare or more of
// the RMS the model without it leaves there: a rod at its end stop reads flat, a reading that
// rounds off at its largest strokes (a valve's gain, a pump that sags) is no end stop.
//
// Its share of the response error (RunResidual::described, run_residual.h): the re-run with the
// identified models leaves E (the worst floor's NRMSE); the same re-run with the channel's
// described residual put back where the channel reads it (the force channel's added to the force
// the integrator receives, the measured channel's to the actuator's motion) leaves E_c;
// share = max(0, E - E_c) / E: the part of what the re-run leaves that the description accounts
// for. Shares of several channels need not add to 100 %.

#include <nlohmann/json.hpp>

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "identify/residual/description.h"
#include "identify/run/actuator_path.h"

namespace rths::identify {

inline constexpr double kMinSignalShare = 0.01;     // described RMS / the target's std
inline constexpr double kDescriptionWins = 0.8;     // x the identified model's held-out RMS error
inline constexpr double kProportionalSpread = 0.3;  // |a_high - a_low| / max(|a_low|, |a_high|)
inline constexpr double kFlatShare = 0.25;     // RMS, where a stroke limit acts: with / without it
inline constexpr std::size_t kStepEdge = 100;  // a step lies 1 / kStepEdge of the record in

struct Unexplained {
  int actuator = 0;  // 1-based
  Channel channel = Channel::kMeasured;
  std::string part, channel_word, unit;  // "load cell 1", "force", "N"
  ResidualDescription description;
  std::vector<double> time;     // s, the channel's samples (what `described` is at)
  std::optional<double> share;  // of the re-run's remaining error; absent when not re-run
  // What the description says of a fitted value (findings.h describe_direction_delays: the
  // delay a direction of motion splits), after its signature; empty: nothing.
  std::vector<std::string> notes;
  std::string text() const;  // "unexplained on load cell 1 (force): ...; share 83 %"
  // {part, channel, share_pct (null when not re-run), kinds, periodic {frequency_hz, amplitude,
  // unit, explained_pct}, amplitude {explained_pct, ratio_change_pct, at_input, of_rate,
  // lead_change_s, unit}, direction {explained_pct, asymmetry (asymmetry_pct, %), of_rate,
  // lead_difference_s, hysteresis_width, unit}, time_varying
  // {explained_pct, change_pct, shape, start_pct, end_pct (measured / model - 1 at the record's
  // start and end), at_s (a step's time, an exponential's time constant; null for a line)}, each
  // null when its test found nothing, explained_pct,
  // residual_rms, unit, notes, text}: the figures text() prints, unrounded.
  nlohmann::json json() const;
};

// Takes out of `path` each named effect whose description wins (above): out of its undeclared
// lists and its estimates, into ActuatorPath::not_named.
void judge_named(ActuatorPath& path);

// Each channel of `path` whose residual the description reports (above), against the final
// model without what judge_named took out (ActuatorPath::not_named).
std::vector<Unexplained> describe_unexplained(const ActuatorPath& path);

// Each described channel's noise judged again on what its descriptions leave together (sensors.h
// white_noise, noise_named): the sensor's noise estimate updated, "noise" no longer named where
// it falls below the thresholds (a ripple's steps are not noise).
void judge_noise_beside(ActuatorPath& path, const std::vector<Unexplained>& described);

// The prediction of `channel`'s final model with `effects` taken back out (sensors.h
// without_named), at every sample: the model the report stands by when `effects` are the ones
// the description beat (not_named_on).
std::vector<double> prediction_without(const ActuatorPath& path, Channel channel,
                                       const std::vector<std::string>& effects);
std::vector<std::string> not_named_on(const ActuatorPath& path, Channel channel);

// `value` with `digits` significant digits ("0.0123").
std::string number_text(double value, int digits = 3);
// `value` with `decimals` after the point ("2.50").
std::string fixed_text(double value, int decimals);

// [item.json(), ...] for the report's lists.
template <class Item>
nlohmann::json json_array(const std::vector<Item>& items) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& item : items) out.push_back(item.json());
  return out;
}

}  // namespace rths::identify
