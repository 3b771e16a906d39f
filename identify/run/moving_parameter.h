#pragma once
// A parameter that moved over the run, held as it moved: the re-run (run_residual.h) and the
// written study (run_config.h) use the fitted shape of a time-varying stiffness, gain or delay,
// not one constant.
//
// Input: an actuator path (actuator_path.h) whose channel's final model holds
// time_varying_stiffness (channel force), time_varying_gain or time_varying_delay (channel
// measured) with its kDriftTerms coefficients c (model.h: v(s) = v + D(s; c); a gain
// v (1 + D(s; c))), v the path's fitted constant (fitted_stiffness N/m, fitted_gain, fitted_delay s).
//   path       v at the centres of kMovingWindows windows of the channel's record, fitted as a
//              line, a step or an exponential (drift_shape.h fit_shape): v(t) = shape.value_at(t).
//   stiffness  a stage at the end of the actuator's chain (it passes the displacement x, m, that
//              the specimen sees) adds (v(t) - v) s x to the force the load cell reads, s the
//              displacement sensor's scale (the fit's stiffness is on the read displacement s x).
//   gain       a stage at the end of the chain multiplies the displacement by v(t) / v.
//   delay      the case's shift stage becomes a trace stage (proto/stages.proto Trace: a shift
//              whose delay follows samples, linear between them) of max(0, v(t)) at kTraceSamples
//              times evenly over the record (its kMovingWindows windows end to end), the shift's amplitude gain kept.
// A channel's described trend (unexplained.h, description.h time_varying: the measured / model
// ratio 1 + rho(t) over the record, fitted as a shape) moves a parameter too: on specimen N's
// force channel the stiffness k (1 + rho(t)), k the one the re-run holds (the fitted where the
// specimen is re-run, else the declared); on actuator N's measured channel the gain
// g (1 + rho(t)), g the fitted. They are held by the same stages.
// A study has no time-varying stiffness or gain (proto/config.proto): the written study holds
// their constant and says so (moving_not_written); a moving delay is written as its trace stage.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/delay.h"
#include "identify/residual/drift_shape.h"
#include "identify/run/actuator_path.h"
#include "rths/proto/config.pb.h"

namespace rths::identify {

struct Unexplained;

inline constexpr std::size_t kMovingWindows = 20;
inline constexpr std::size_t kTraceSamples = 200;

struct MovingParameter {
  int actuator = 0;  // 1-based
  Channel channel = Channel::kMeasured;
  std::string part, effect;  // "specimen 1", "time_varying_stiffness"
  std::string unit;          // "N/m", "" (a gain) or "s"
  double constant = 0.0;     // v: what a model without the drift holds, in `unit`
  ShapeFit shape;            // v(t), in `unit`
};

// The moving path of `effect` on `channel` of `path` from its estimate's drift coefficients
// (ActuatorPath::estimates, estimate_effects ran); nullopt for any other effect or no estimate.
std::optional<MovingParameter> moving_parameter(const ActuatorPath& path, Channel channel,
                                                const std::string& effect);

// Every moving parameter `path` names (undeclared on channel measured, specimen_undeclared on
// channel force; a rejected effect is not named any more).
std::vector<MovingParameter> moving_parameters(const ActuatorPath& path);

// One quantity, one finding. Where a path names a parameter moving (time_varying_stiffness on
// channel force, time_varying_gain or time_varying_delay on channel measured) and also its
// constant off the declared ("stiffness change", "gain error", "delay change"), the record shows
// the quantity moving, not one changed value: the constant's name leaves the named list into
// ActuatorPath::merged_constants (not rejected: the fitted constant stays in the re-run and the
// written study, under the moving path) and the moving finding states the declared value beside
// its start and end (declared_constant). Run after judge_named and judge_plausible.
void merge_constant_changes(ActuatorPath& path);

// `rejected` (a moving parameter the re-run rejected, taken out of `named`, one of `path`'s named
// lists): the constant change it had merged is named again on its own, since the record still
// shows the value off the declared once the path is not held moving.
void restore_merged_constant(ActuatorPath& path, std::vector<std::string>& named,
                             const std::string& rejected);

// The constant change `moving_effect` holds ("stiffness change" for "time_varying_stiffness",
// "gain error", "delay change"); empty for any other effect.
std::string constant_change_of(const std::string& moving_effect);

// The declared value of the quantity `moving_effect` moves, in its MovingParameter unit (N/m,
// a gain, s).
double declared_constant(const ActuatorPath& path, const std::string& moving_effect);

// The parameter `described`'s trend moves (above), with `specimen_rerun`: whether the re-run
// holds the fitted specimen; nullopt without a trend, on another part or with no constant.
std::optional<MovingParameter> described_moving(const Unexplained& described,
                                                const ActuatorPath& path, bool specimen_rerun);

// The stage that holds a moving stiffness or gain at the end of the actuator's chain, as above;
// nullptr for a delay (hold_moving_delay holds it). `displacement_scale`: s, 1 for a true sensor.
std::unique_ptr<core::DelayStage> moving_stage(const MovingParameter& moving,
                                               double displacement_scale);

// `study_case`'s shift stage replaced by the moving delay's trace stage; false (nothing changed)
// for another parameter or a case without a shift stage.
bool hold_moving_delay(const MovingParameter& moving, config::Case& study_case);

// Why the written study holds `moving` as its constant ("specimen 1: time_varying_stiffness: ..."),
// empty for a delay, which it holds moving.
std::string moving_not_written(const MovingParameter& moving);

}  // namespace rths::identify
