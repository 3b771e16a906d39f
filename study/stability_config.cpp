#include "study/stability_config.h"

#include <memory>
#include <stdexcept>

#include "core/coupled_stability.h"
#include "core/loop_critical_delay.h"
#include "core/simulation.h"
#include "study/compensation_config.h"
#include "study/study.h"

namespace rths::study {

core::CompensatedStability compensated_stability(
    core::IntegratorKind kind, double period, double zeta, double alpha, double dt,
    const google::protobuf::RepeatedPtrField<config::DelayStage>& actuator,
    const config::Compensation* compensation, double max_extra_delay, int branches) {
  if (!(dt > 0)) throw std::invalid_argument("stability: dt must be > 0 s");
  if (!(max_extra_delay >= 0))
    throw std::invalid_argument("stability: max_extra_delay must be >= 0 s");
  core::DelayChain loop = make_delay_chain(actuator, dt, {});
  if (compensation) loop.set_compensator(make_compensator(*compensation, dt, "compensation"));
  return core::compensated_stability(kind, period, zeta, alpha, dt, loop, max_extra_delay,
                                     branches);
}

double simulated_growth(core::IntegratorKind kind, double period, double zeta, double alpha,
                        double dt,
                        const google::protobuf::RepeatedPtrField<config::DelayStage>& actuator,
                        const config::Compensation* compensation, double extra_delay,
                        double duration) {
  core::DelayChain chain = make_delay_chain(actuator, dt, {});
  if (extra_delay > 0.0) chain.add(std::make_unique<core::TimeShift>(extra_delay, dt));
  if (compensation) chain.set_compensator(make_compensator(*compensation, dt, "compensation"));
  return core::simulated_growth(kind, period, zeta, alpha, dt, std::move(chain), duration);
}

std::optional<core::CriticalDelayCheck> check_setup_critical_delay(const PreparedStudy& prepared,
                                                                   const core::HybridSetup& setup,
                                                                   double lag) {
  if (prepared.base.partition.actuator_storeys.empty()) return std::nullopt;
  // Each link's specimen with its dashpot and mass, which come back late with its force.
  const std::vector<core::DelayedPart> parts = core::setup_loop_parts(
      setup, std::vector<double>(setup.partition.actuator_storeys.size(), 0.0));
  return core::check_loop_critical_delay(setup.model, parts, setup.integrator, setup.dt, lag);
}

std::optional<core::CriticalDelayCheck> check_lag_critical_delay(const PreparedStudy& prepared,
                                                                 double lag) {
  return check_setup_critical_delay(prepared, prepared.base, lag);
}

}  // namespace rths::study
