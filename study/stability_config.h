#pragma once
// The stability analyses of core/stability.h for a study case's delay stages and compensation
// config messages.

#include <optional>

#include "core/stability.h"
#include "rths/proto/config.pb.h"

namespace rths::core {
struct HybridSetup;
}  // namespace rths::core

namespace rths::study {

struct PreparedStudy;

// The one pre-run judgement of a lag (s) on a study: core::check_loop_critical_delay (core/loop_critical_delay.h) of `setup`'s
// model, integrator and dt with its links' specimens (stiffness, dashpot, mass; exact on one DOF,
// the coupled analysis where the modes do not decouple them). Empty when the structure has no
// experimental part.
std::optional<core::CriticalDelayCheck> check_setup_critical_delay(const PreparedStudy& prepared,
                                                                   const core::HybridSetup& setup,
                                                                   double lag);
// The same on the study's base setup, for a lag given directly (e.g. an identified actuator's
// nominal delay).
std::optional<core::CriticalDelayCheck> check_lag_critical_delay(const PreparedStudy& prepared,
                                                                 double lag);

// compensated_stability (core/stability.h) for a study case's delay stages and compensation
// (`compensation` may be null: uncompensated), built at dt. Throws std::invalid_argument naming
// what cannot be analysed (an implicit integrator, a jitter or trace stage...) or what the blocks'
// constructors refuse.
core::CompensatedStability compensated_stability(
    core::IntegratorKind kind, double period, double zeta, double alpha, double dt,
    const google::protobuf::RepeatedPtrField<config::DelayStage>& actuator,
    const config::Compensation* compensation, double max_extra_delay, int branches = 3);

// simulated_growth (core/stability.h) with the compensated actuator and `extra_delay` more: peak
// |u| over the last third of the run divided by that over the first third (> 1 grows, < 1 decays).
double simulated_growth(core::IntegratorKind kind, double period, double zeta, double alpha,
                        double dt,
                        const google::protobuf::RepeatedPtrField<config::DelayStage>& actuator,
                        const config::Compensation* compensation, double extra_delay,
                        double duration);

}  // namespace rths::study
