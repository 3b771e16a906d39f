#pragma once
// One verdict over every part of a run's loop: each difference between what the record shows
// and what the header declared, in one list, whatever channel found it.
//
// Input: a run's parts identified from its record (run_record.h): its links, its actuator paths,
// its re-run (absent when not made) and its clock ("lockstep", "real_time").
// Output, one Finding per difference:
//   part       "platform" (steps on late answers and overruns, first: what the platform did
//              before what the rig did), "link to node N" (network), "actuator N" (lag, gain,
//              backlash, velocity and stroke limits), "specimen N" (stiffness, damping,
//              hysteresis), "displacement sensor N" and "load cell N" (offset and drift, noise;
//              the displacement sensor's scale: sensors.h): N is the node id or the 1-based
//              actuator;
//   effect     the effect's name (identify/model/effects.h, or "gain error", "delay change",
//              "stiffness change", the network's "drifting delay", "clock offset", ...);
//   magnitude  its parameters with standard errors and units (effect_parameters.h), or the
//              fitted value beside the declared one; a parameter that moves over the run (a
//              time-varying stiffness, gain or delay: the fitted value v plus the drift D(s; c),
//              identify/model/model.h) as moving: v(t) at the centres of kMovingWindows windows
//              fitted as a line, a step or an exponential (drift_shape.h), with its start and end
//              value, the step's time or the time constant;
//   evidence   the held-out error of its channel before and after the effect: a share of the
//              signal's std for the actuator and force channels, s RMS for a link;
//   response   the worst floor's NRMSE the re-run loses without it and its share of the removals
//              (run_residual.h), or why the re-run cannot hold it (counted as unexplained: a
//              sensor's noise, whose samples no re-run replays).

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "identify/fit/effect_parameters.h"
#include "identify/residual/drift_shape.h"
#include "identify/run/actuator_path.h"
#include "identify/run/network_path.h"
#include "identify/run/run_residual.h"

namespace rths::identify {

struct Unexplained;

struct Finding {
  std::string part, effect;
  std::vector<ParameterEstimate> parameters;  // empty where `magnitude` says it in words
  std::string magnitude;                      // the parameters as text
  double heldout_before = 0.0, heldout_after = 0.0;
  std::string heldout_unit;                // "of the signal's std" or "s RMS"
  std::optional<double> response_removed;  // NRMSE of the worst floor, absent when not re-run
  double response_share = 0.0;             // of the re-run's removals
  std::string not_rerun;                   // why the re-run leaves it out; empty when re-run
  // A parameter that moves over the run (time_varying_stiffness, _gain, _delay): its path
  // through the record's kMovingWindows windows fitted as a shape (drift_shape.h), in
  // `moving_unit`; absent for a constant.
  std::optional<ShapeFit> moving;
  std::string moving_unit;
};

// Every effect of each identified channel of `path` with its parameters (ActuatorPath::estimates),
// once, after its channels were identified.
void estimate_effects(ActuatorPath& path);

// @pre estimate_effects ran on every actuator path.
// A delay longer one way of motion than the other: where a path's "delay change" finding has,
// on its measured channel's described residual (unexplained.h), a lead that differs by the
// direction of motion (of_rate) by at least kSplitDelayShare of the change, the change is the
// mean of two delays, not one delay that changed: the finding leaves the named list and the
// description says the delay rising and falling (the fitted mean -+ half the lead difference)
// beside the declared one. Every section says the same: the path's named effects lose "delay
// change" (ActuatorPath::not_named gains it, delay_by_direction holds the description's words)
// and the re-run's share of it (`residual`, when re-run) reads kDelaysByDirection. The re-run and
// the written study keep holding the fitted mean.
void describe_direction_delays(std::vector<ActuatorPath>& actuators,
                               std::vector<Unexplained>& unexplained,
                               std::vector<Finding>& findings, RunResidual* residual);
inline constexpr double kSplitDelayShare = 0.5;
inline constexpr const char* kDelaysByDirection =
    "the mean of two delays by the direction of motion";

std::vector<Finding> collect_findings(const std::vector<NetworkPath>& links,
                                      const std::vector<ActuatorPath>& actuators,
                                      const RunResidual* residual, const std::string& clock);

// "undeclared effects, every part: none" or a line per finding, then what the re-run leaves
// unexplained.
std::string findings_text(const std::vector<Finding>& findings, const RunResidual* residual);
nlohmann::json findings_json(const std::vector<Finding>& findings);
// Parameters as the run report's JSON gives them: [{name, value, std_error, unit}].
nlohmann::json parameters_json(const std::vector<ParameterEstimate>& parameters);

}  // namespace rths::identify
