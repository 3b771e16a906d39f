#pragma once
// One actuator's path as identified from a run's record: what the case declared, what the fit
// found (gain, delay, the effects beyond the declared model), and the identification itself.

#include <optional>
#include <string>
#include <vector>

#include "identify/fit/effect_parameters.h"
#include "identify/fit/identify.h"

namespace rths::identify {

// One effect of a channel's final model with its parameters (effect_parameters.h; an offset
// drift as the sensor_drift stage holds it: the offset at t = 0 of the run and the drift per
// second), computed once (findings.h estimate_effects): the channel sections, the JSON and the
// findings all print these.
struct EffectEstimate {
  Channel channel = Channel::kMeasured;
  Effect effect = Effect::kDelay;
  bool added = false;  // beyond the channel's declared model (a search step or its start)
  // Its own part of the channel's held-out error, for one a search step added; absent for one the
  // search started from (a proposed specimen kind) or the declared model held.
  std::optional<double> share;
  std::vector<ParameterEstimate> parameters;
};

struct ActuatorPath {
  int actuator = 0;                   // 1-based
  std::vector<std::string> declared;  // the case's stages, as effects
  double declared_gain = 1.0, fitted_gain = 1.0;
  // The declared pure delay and the fitted one (s): a declared shift's, or 0 when the run declared
  // no actuator stage at all (delay_declared); both 0 and delay_declared false when the declared
  // stages hold no shift (a first-order lag, ...).
  bool delay_declared = false;
  double declared_delay = 0.0, fitted_delay = 0.0;
  Identification id;                    // channels measured and force
  std::vector<std::string> undeclared;  // effects named beyond the declared model
  // The specimen and the load cell behind this actuator (channel force), against the study's
  // declared storey model: its restoring force's kind as effects (linear: stiffness; bouc_wen:
  // + bouc_wen; bilinear: + elastoplastic) and its initial stiffness (N/m).
  std::vector<std::string> declared_specimen;
  double declared_stiffness = 0.0, fitted_stiffness = 0.0;  // N/m
  // Effects the force channel needed beyond the declared specimen ("bouc_wen", "offset_drift",
  // ...) and "stiffness change" (fitted off the declared one by more than kStiffnessTolerance).
  std::vector<std::string> specimen_undeclared;
  // The sensors (sensors.h): each channel's noise (RMS, m and N) as the record shows it and as
  // the case declared it, and the displacement sensor's scale (1: it reads the truth) with its
  // standard error.
  double displacement_noise = 0.0, force_noise = 0.0;
  double declared_displacement_noise = 0.0, declared_force_noise = 0.0;
  double displacement_scale = 1.0, displacement_scale_error = 0.0;
  // Every effect of each channel's final model: the search's steps first in their order, then the
  // other effects beyond the declared model, then the declared ones.
  std::vector<EffectEstimate> estimates;
  // Effects a channel's search added or its fit implied that the form-free description of the
  // residual beat on held-out data (unexplained.h judge_named): named nowhere, described instead.
  struct NotNamed {
    Channel channel = Channel::kMeasured;
    std::string effect;
  };
  std::vector<NotNamed> not_named;
  // Effects whose term the record shows is not the library's form (unexplained.h judge_named:
  // its coefficient differs between the smaller and the larger half of its own term) but whose
  // fitted term the re-run holds as the nearest form it has: named nowhere, their words (`why`)
  // said beside the channel's description; the re-run and the written study hold them
  // (sensors.h rig_models).
  struct HeldNotNamed {
    Channel channel = Channel::kMeasured;
    std::string effect, why;
  };
  std::vector<HeldNotNamed> held_not_named;
  // Where a fitted delay off the declared one is two delays by the direction of motion
  // (findings.h describe_direction_delays): what the description says of them (the delay rising
  // and falling, the declared one); "delay change" is then among not_named, and the re-run and the
  // written study hold the fitted mean (rig_models). Empty: one delay.
  std::string delay_by_direction;
  // Constant changes ("stiffness change", "gain error", "delay change") a moving parameter of the
  // same quantity holds (moving_parameter.h merge_constant_changes): named by the moving one only.
  std::vector<std::string> merged_constants;
  // Effects a channel named that made the re-run worse (run_residual.h effects: the identified
  // re-run without the effect has a lower worst-floor NRMSE, by `worsening`): taken out of the
  // named effects, of the re-run and of the written study (sensors.h rig_models), and said as
  // rejected (run_record.h).
  struct Rejected {
    Channel channel = Channel::kMeasured;
    std::string part, effect;  // as the re-run named them ("specimen 1", "bouc_wen")
    double worsening = 0.0;    // NRMSE of the worst floor the effect added, > 0
    // Why, when the magnitude fit badly (plausibility.h: "poorly determined: ..." or
    // "implausible: ..."), judged before any re-run; empty for a re-run's rejection.
    std::string reason;
  };
  std::vector<Rejected> rejected;
  bool was_rejected(Channel channel, const std::string& effect) const {
    for (const auto& r : rejected)
      if (r.channel == channel && r.effect == effect) return true;
    return false;
  }
  const EffectEstimate* estimate(Channel channel, Effect effect) const {
    for (const auto& e : estimates)
      if (e.channel == channel && e.effect == effect) return &e;
    return nullptr;
  }
};

inline constexpr double kStiffnessTolerance = 0.05;  // relative

}  // namespace rths::identify
