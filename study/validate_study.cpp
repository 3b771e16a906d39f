#include "study/study.h"

#include "core/number_text.h"
#include "study/compensation_config.h"
#include "study/known_enums.h"
#include "study/ranges.h"
#include "study/recorders.h"
#include "study/tracking_config.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

// validate_study and its parts: every rule a study must meet before anything is built from it,
// each failure an std::invalid_argument naming the source and the field.
namespace rths::study {
namespace {

[[noreturn]] void fail(const std::string& source, const std::string& message) {
  throw std::invalid_argument(source + ": " + message);
}

void require(bool ok, const std::string& source, const std::string& message) {
  if (!ok) fail(source, message);
}

// A number against its range rule (study/ranges.h), the message prefixed with the source.
void require_in(Quantity quantity, double value, const std::string& field,
                const std::string& source) {
  const std::string message = range_violation(quantity, value, field);
  if (!message.empty()) fail(source, message);
}

// A lag in seconds (core::check_lag); a time constant must also be > 0.
void require_lag(double value, const std::string& field, const std::string& source,
                 bool zero_allowed, bool allow_long_lag) {
  require(zero_allowed || value > 0, source,
          field + " must be > 0 s, got " + core::format_number(value));
  require_in(allow_long_lag ? Quantity::kLongLag : Quantity::kLag, value, field, source);
}

// The stages that model the actuator's lag; false for any other kind.
bool validate_lag_stage(const config::DelayStage& stage, const std::string& where,
                        const std::string& source, bool long_lag) {
  using K = config::DelayStage::KindCase;
  switch (stage.kind_case()) {
    case K::kShift:
      require_lag(stage.shift().delay(), where + ".shift.delay", source, true, long_lag);
      break;
    case K::kEq1:
      require_lag(stage.eq1().delay(), where + ".eq1.delay", source, true, long_lag);
      break;
    case K::kEq1Lag:
      require_lag(stage.eq1_lag().delay(), where + ".eq1_lag.delay", source, true, long_lag);
      break;
    case K::kFirstOrder:
      require_lag(stage.first_order().time_constant(), where + ".first_order.time_constant", source,
                  false, long_lag);
      break;
    case K::kTransferFunction:
      require(!stage.transfer_function().denominator().empty(), source,
              where + ".transfer_function.denominator is empty");
      break;
    case K::kJitter:
      require_lag(stage.jitter().mean_delay(), where + ".jitter.mean_delay", source, true,
                  long_lag);
      require_lag(stage.jitter().std_dev(), where + ".jitter.std_dev", source, true, long_lag);
      break;
    case K::kTrace:
      require(!stage.trace().path().empty(), source, where + ".trace.path is empty");
      break;
    case K::kBenchmark: break;
    case K::kTrackingLoop:
      // The rest is checked where it is built (core::TrackingLoop), naming the field; a given
      // plant value here, so that no study is accepted with an explicit 0 its default would hide.
      if (stage.tracking_loop().has_benchmark_plant()) {
        try {
          (void)benchmark_plant_parameters(stage.tracking_loop().benchmark_plant());
        } catch (const std::invalid_argument& e) {
          fail(source, where + ".tracking_loop." + e.what());
        }
      }
      break;
    default: return false;
  }
  return true;
}

// The rig's other effects: motion limits, sensor errors and the specimen's parasitic forces.
void validate_rig_effect_stage(const config::DelayStage& stage, const std::string& where,
                               const std::string& source) {
  using K = config::DelayStage::KindCase;
  switch (stage.kind_case()) {
    case K::kBacklash:
      require(stage.backlash().width() >= 0.0 && stage.backlash().width() <= 1.0, source,
              where + ".backlash.width must be in [0, 1] m, got " +
                  core::format_number(stage.backlash().width()));
      break;
    case K::kVelocityLimit:
      require(stage.velocity_limit().max_velocity() > 0.0 &&
                  stage.velocity_limit().max_velocity() <= 100.0,
              source,
              where + ".velocity_limit.max_velocity must be in (0, 100] m/s, got " +
                  core::format_number(stage.velocity_limit().max_velocity()));
      break;
    case K::kStrokeLimit:
      require(stage.stroke_limit().stroke() > 0.0 && stage.stroke_limit().stroke() <= 10.0, source,
              where + ".stroke_limit.stroke must be in (0, 10] m, got " +
                  core::format_number(stage.stroke_limit().stroke()));
      break;
    case K::kSensorDrift: {
      const auto& d = stage.sensor_drift();
      require(std::isfinite(d.displacement_offset()) && std::isfinite(d.displacement_drift()) &&
                  std::isfinite(d.force_offset()) && std::isfinite(d.force_drift()),
              source, where + ".sensor_drift: every offset and drift must be finite");
      require(d.displacement_scale() >= 0.0 && d.displacement_scale() <= 10.0, source,
              where + ".sensor_drift.displacement_scale must be in [0, 10] (0 = 1), got " +
                  core::format_number(d.displacement_scale()));
      break;
    }
    case K::kViscousForce:
      require(stage.viscous_force().damping() >= 0.0 && stage.viscous_force().damping() <= 1e9,
              source,
              where + ".viscous_force.damping must be in [0, 1e9] N s/m, got " +
                  core::format_number(stage.viscous_force().damping()));
      break;
    case K::kInertiaForce:
      require(stage.inertia_force().mass() >= 0.0 && stage.inertia_force().mass() <= 1e9, source,
              where + ".inertia_force.mass must be in [0, 1e9] kg, got " +
                  core::format_number(stage.inertia_force().mass()));
      break;
    case K::kFrictionForce: {
      const auto& f = stage.friction_force();
      require(f.friction_force() >= 0.0 && f.friction_force() <= 1e9, source,
              where + ".friction_force.friction_force must be in [0, 1e9] N, got " +
                  core::format_number(f.friction_force()));
      require(f.smoothing_velocity() > 0.0 && f.smoothing_velocity() <= 100.0, source,
              where + ".friction_force.smoothing_velocity must be in (0, 100] m/s, got " +
                  core::format_number(f.smoothing_velocity()));
      break;
    }
    case K::kForceDelay:
      require(stage.force_delay().delay() >= 0.0 && stage.force_delay().delay() <= 1.0, source,
              where + ".force_delay.delay must be in [0, 1] s, got " +
                  core::format_number(stage.force_delay().delay()));
      break;
    default: break;  // a lag stage (validate_lag_stage) or none (validate_delay_stage)
  }
}

void validate_delay_stage(const config::DelayStage& stage, const std::string& where,
                          const std::string& source, bool long_lag) {
  require(stage.amplitude_gain() >= 0 && stage.amplitude_gain() <= 10, source,
          where + ".amplitude_gain must be in [0, 10] (0 means 1), got " +
              core::format_number(stage.amplitude_gain()));
  if (stage.kind_case() == config::DelayStage::KIND_NOT_SET)
    fail(source, where + " has no kind (shift, eq1, eq1_lag, ...)");
  if (!validate_lag_stage(stage, where, source, long_lag))
    validate_rig_effect_stage(stage, where, source);
}

void validate_structure(const config::Structure& structure, const std::string& source) {
  if (structure.has_sdof()) {
    const config::Sdof& sdof = structure.sdof();
    // Given, the mass must be one: an explicit 0 is not quietly run as 1 kg.
    require(!sdof.has_mass() || sdof.mass() > 0, source,
            "structure.sdof.mass must be > 0 kg, got " + core::format_number(sdof.mass()) +
                " (omit it for 1 kg: at a fixed period the response does not depend on it)");
    require(!(sdof.has_mass() && sdof.period() > 0 && sdof.stiffness() > 0), source,
            "structure.sdof: mass, period and stiffness are all given; give two (the mass is "
            "derived from period and stiffness)");
    require(sdof.stiffness() >= 0, source, "structure.sdof.stiffness must be > 0 N/m");
    if (sdof.period() != 0)
      require_in(Quantity::kPeriod, sdof.period(), "structure.sdof.period", source);
    require(sdof.period() > 0 || (sdof.mass() > 0 && sdof.stiffness() > 0), source,
            "structure.sdof needs a period, or both mass and stiffness");
  } else if (structure.has_shear_building()) {
    const auto& building = structure.shear_building();
    require(building.storey_mass_size() > 0, source,
            "structure.shear_building.storey_mass is empty");
    require(building.storey_mass_size() == building.storey_stiffness_size(), source,
            "structure.shear_building: storey_mass and storey_stiffness differ in length");
    for (int i = 0; i < building.storey_mass_size(); ++i)
      require(building.storey_mass(i) > 0, source,
              "structure.shear_building.storey_mass[" + std::to_string(i) +
                  "] must be > 0 kg, got " + core::format_number(building.storey_mass(i)));
  } else if (!structure.has_matrices()) {
    fail(source, "structure needs sdof, shear_building or matrices");
  }
  const bool rayleigh = structure.damping().has_rayleigh();
  require_in(Quantity::kDampingRatio,
             rayleigh ? structure.damping().rayleigh().zeta() : structure.damping().modal_zeta(),
             rayleigh ? "structure.damping.rayleigh.zeta" : "structure.damping.modal_zeta", source);
}

void validate_cases(const config::Study& study, const std::string& source) {
  for (int i = 0; i < study.cases_size(); ++i) {
    const config::Case& c = study.cases(i);
    const std::string where = "cases[" + std::to_string(i) + "] '" + c.name() + "'";
    require(!c.name().empty(), source,
            "cases[" + std::to_string(i) + "] has no name: every case is named (--case NAME)");
    for (int j = 0; j < i; ++j) {
      require(study.cases(j).name() != c.name(), source,
              "cases[" + std::to_string(i) + "] repeats the name '" + c.name() + "' of cases[" +
                  std::to_string(j) + "]: case names must be unique");
    }
    for (int j = 0; j < c.delay_size(); ++j) {
      validate_delay_stage(c.delay(j), where + " delay[" + std::to_string(j) + "]", source,
                           study.allow_long_lag());
    }
    for (int j = 0; j < c.link_size(); ++j) {
      const std::string link = where + " link[" + std::to_string(j) + "].";
      validate_link_lag(c.link(j).to_node(), link + "to_node", study.allow_long_lag(), source);
      validate_link_lag(c.link(j).from_node(), link + "from_node", study.allow_long_lag(), source);
    }
    for (int j = 0; j < c.compensation_size(); ++j) {
      try {
        validate_compensation(c.compensation(j),
                              where + " compensation[" + std::to_string(j) + "]");
      } catch (const std::invalid_argument& e) {
        fail(source, e.what());
      }
    }
    if (c.has_force_predictor()) {
      try {
        validate_force_predictor(c.force_predictor(), study.integrator().dt(),
                                 where + " force_predictor");
      } catch (const std::invalid_argument& e) {
        fail(source, e.what());
      }
    }
  }
}

void validate_sweep(const config::Study& study, const std::string& source) {
  for (double period : study.sweep().periods())
    require_in(Quantity::kPeriod, period, "sweep.periods", source);
  for (double delay : study.sweep().delays())
    require_lag(delay, "sweep.delays", source, true, study.allow_long_lag());
  for (double dt : study.sweep().dts()) require_in(Quantity::kStep, dt, "sweep.dts", source);
  for (double k : study.sweep().stiffnesses())
    require(k > 0, source, "sweep.stiffnesses must be > 0 N/m");
  for (double a : study.sweep().experimental_fractions()) {
    require_in(Quantity::kFraction, a, "sweep.experimental_fractions", source);
  }
}

// 0 means "the default" for these fields; any other value must be inside its range.
void require_unset_or_in(Quantity quantity, double value, const std::string& field,
                         const std::string& source) {
  if (value != 0) require_in(quantity, value, field, source);
}

// 0 = off for each part; a spike lasts fewer steps than its period, a burst starts at step 1 or
// later (step 0 sends no command).
void validate_network_emulation(const config::NetworkEmulation& net, const std::string& where,
                                bool allow_long_lag, const std::string& source) {
  require_in(Quantity::kFraction, net.drift_rate(), where + ".drift_rate (s per s)", source);
  require_lag(net.spike_delay(), where + ".spike_delay", source, true, allow_long_lag);
  require_unset_or_in(Quantity::kCount, net.spike_every(), where + ".spike_every", source);
  require_unset_or_in(Quantity::kCount, net.spike_steps(), where + ".spike_steps", source);
  require(net.spike_steps() < net.spike_every() || net.spike_steps() == 0, source,
          where + ".spike_steps = " + std::to_string(net.spike_steps()) +
              " must be below spike_every = " + std::to_string(net.spike_every()) +
              " (a spike shorter than its period)");
  require_unset_or_in(Quantity::kCount, net.drop_first_step(), where + ".drop_first_step", source);
  require_unset_or_in(Quantity::kCount, net.drop_steps(), where + ".drop_steps", source);
  require(net.drop_steps() == 0 || net.drop_first_step() >= 1, source,
          where + ".drop_first_step must be >= 1 with drop_steps (step 0 sends no command)");
}

void validate_deployment(const config::Deployment& d, bool allow_long_lag,
                         const std::string& source) {
  const std::string at = "deployment.";
  require_in(Quantity::kDdsDomain, d.domain_id(), at + "domain_id", source);
  for (int i = 0; i < d.nodes_size(); ++i) {
    const std::string node = at + "nodes[" + std::to_string(i) + "].";
    for (const auto& [name, lag] : {std::pair{"receive_lag", &d.nodes(i).receive_lag()},
                                    std::pair{"send_lag", &d.nodes(i).send_lag()}}) {
      validate_link_lag(*lag, node + name, allow_long_lag, source);
    }
  }
  require_unset_or_in(Quantity::kTimeout, d.start_timeout(), at + "start_timeout", source);
  require_unset_or_in(Quantity::kTimeout, d.heartbeat_period(), at + "heartbeat_period", source);
  require_unset_or_in(Quantity::kTimeout, d.liveliness_timeout(), at + "liveliness_timeout",
                      source);
  require_unset_or_in(Quantity::kTimeout, d.step_timeout(), at + "step_timeout", source);
  require_unset_or_in(Quantity::kFraction, d.feedback_wait_fraction(),
                      at + "feedback_wait_fraction", source);
  require_unset_or_in(Quantity::kLag, d.spin_margin(), at + "spin_margin", source);
  if (d.max_overrun_fraction() >= 0)
    require_in(Quantity::kFraction, d.max_overrun_fraction(),
               at + "max_overrun_fraction (< 0: off)", source);
  if (d.min_answer_fraction() >= 0)
    require_in(Quantity::kFraction, d.min_answer_fraction(), at + "min_answer_fraction (< 0: off)",
               source);
  require_unset_or_in(Quantity::kCount, d.max_missed_answers(), at + "max_missed_answers", source);
  require_unset_or_in(Quantity::kCount, d.command_watchdog_periods(),
                      at + "command_watchdog_periods", source);
  if (d.pin_loop() || d.loop_cpu() > 0)
    require_in(Quantity::kCpu, d.loop_cpu(), at + "loop_cpu", source);
  if (d.realtime_priority() > 0 || d.realtime_priority() < -1) {
    require_in(Quantity::kFifoPriority, d.realtime_priority(),
               at + "realtime_priority (0 or -1: off)", source);
    require(d.clock() == config::Deployment::REAL_TIME, source,
            "deployment.realtime_priority applies to clock: REAL_TIME only (a lockstep run "
            "has no deadline to keep)");
    require(d.wait_policy() != config::WAIT_SPIN, source,
            "deployment.realtime_priority with wait_policy: WAIT_SPIN would let the spinning "
            "loop shut the DDS receive threads out of its CPU; use WAIT_SLEEP_THEN_SPIN");
  }
  require(d.limits().max_displacement() >= 0 && d.limits().max_velocity() >= 0, source,
          "deployment.limits.max_displacement and max_velocity must be >= 0 (0 = no limit)");
}

}  // namespace

void validate_link_lag(const config::LinkLag& lag, const std::string& where, bool allow_long_lag,
                       const std::string& source) {
  require_lag(lag.one_way_delay(), where + ".one_way_delay", source, true, allow_long_lag);
  require_lag(lag.jitter(), where + ".jitter", source, true, allow_long_lag);
  require(
      lag.loss() >= 0 && lag.loss() < 1, source,
      where + ".loss = " + core::format_number(lag.loss()) + " is outside [0, 1) (a probability)");
  validate_network_emulation(lag.network(), where + ".network", allow_long_lag, source);
}

void validate_study(const config::Study& study, const std::string& source) {
  require_known_enums(study, source);  // before anything switches over one
  require(study.has_structure(), source, "structure is missing");
  validate_structure(study.structure(), source);
  require(std::isfinite(study.servo().rate()) && study.servo().rate() >= 0, source,
          "servo.rate must be >= 0 Hz (0 = the integrator's rate), got " +
              core::format_number(study.servo().rate()));
  require_unset_or_in(Quantity::kStep, study.integrator().dt(),
                      "integrator.dt (0 = the record's step)", source);
  const auto& sub = study.substructuring();
  require_in(Quantity::kFraction, sub.experimental_fraction(),
             "substructuring.experimental_fraction", source);
  require(sub.experimental_storeys().empty() || sub.experimental_fraction() == 0, source,
          "substructuring: give experimental_fraction or experimental_storeys, not both");
  if (study.structure().has_matrices()) {
    require(sub.experimental_storeys().empty() && sub.experimental_fraction() == 0, source,
            "substructuring: a structure given by matrices is split at experimental_dofs, not by "
            "storeys");
  } else {
    require(sub.experimental_dofs().empty() ||
                (sub.experimental_storeys().empty() && sub.experimental_fraction() == 0 &&
                 (sub.model().kind_case() == config::RestoringForce::KIND_NOT_SET ||
                  sub.model().has_linear())),
            source,
            "substructuring.experimental_dofs on a shear building takes its matrices: it needs a "
            "linear storey model and no experimental_fraction or experimental_storeys");
  }
  require_unset_or_in(Quantity::kMotionScale, study.motion().scale(), "motion.scale (0 means 1)",
                      source);
  require(study.motion().duration() >= 0, source, "motion.duration must be >= 0 s");
  validate_cases(study, source);
  validate_sweep(study, source);
  validate_deployment(study.deployment(), study.allow_long_lag(), source);
  validate_recorders(study, source);
}

}  // namespace rths::study
