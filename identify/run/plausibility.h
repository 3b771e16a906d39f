#pragma once
// Magnitudes that fit badly say so: a named effect whose fitted magnitude the record cannot
// support is reported "poorly determined" or "implausible" with the reason, and left out of the
// re-run and the written study (moved to ActuatorPath::rejected with that reason).
//
// Input: an effect's parameters as estimated (effect_parameters.h: value, standard error, SI
// unit) and the largest |displacement| (m) its channel's model was driven by (the force channel's
// model input; the command on the actuator channel).
//   poorly determined  a parameter whose standard error is at least kPoorlyDetermined x |value|
//                      (its 68 % interval reaches 0: the record does not tell it from none);
//                      for a drift (time_varying_*: kDriftTerms coefficients <prefix>_cK) every
//                      coefficient so: no change the windows show.
//   implausible        a yield the record never reached: Bouc–Wen's yield_drift, or the
//                      elasto-plastic yield_force / plastic_stiffness (m), at least
//                      kYieldBeyondReach x the largest |displacement|: the specimen was elastic
//                      throughout, so no window holds evidence of the yield the fit put there.
//                      On the force channel, an elasto-plastic yield whose loops the record
//                      does not close: what the force read dissipates beyond the rest of the
//                      model, sum F dx over the record (sensors' force and the model's input
//                      displacement), below kMinYieldDissipation x what the model's yield term
//                      dissipates along the same path. A yield plateau dissipates its loop's area
//                      every cycle; a specimen that cracked or softened stays elastic on either
//                      side of the change and encloses none (its drop is a step change, named by
//                      the stiffness).
// Every other effect, and one with no parameters (a changed value: "gain error", ...), passes.

#include <optional>
#include <string>
#include <vector>

#include "identify/fit/effect_parameters.h"
#include "identify/run/actuator_path.h"

namespace rths::identify {

inline constexpr double kPoorlyDetermined = 1.0;     // standard error / |value|
inline constexpr double kYieldBeyondReach = 1.0;     // x the largest |displacement|
inline constexpr double kMinYieldDissipation = 0.5;  // x the yield term's own

// "poorly determined: ..." or "implausible: ..." with the reason; nullopt when it fits well.
std::optional<std::string> implausible(Effect effect,
                                       const std::vector<ParameterEstimate>& parameters,
                                       double largest_displacement);

// Each named effect of `path` (undeclared, specimen_undeclared) that `implausible` judges moved to
// its rejected effects with the reason. Call after estimate_effects, before the re-run.
void judge_plausible(ActuatorPath& path);

}  // namespace rths::identify
