#include "study/study.h"

#include "core/rig_effects.h"
#include "study/compensation_config.h"
#include "study/delay_trace_file.h"
#include "study/known_enums.h"
#include "study/memory_budget.h"
#include "study/motion_files.h"
#include "study/ranges.h"
#include "study/restoring_force_config.h"
#include "study/structure_config.h"
#include "study/text_columns.h"
#include "study/text_format.h"
#include "study/tracking_config.h"
#include "util/sha256.h"

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace rths::core {
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
  require(zero_allowed || value > 0, source, field + " must be > 0 s, got " + format_number(value));
  require_in(allow_long_lag ? Quantity::kLongLag : Quantity::kLag, value, field, source);
}

void validate_delay_stage(const config::DelayStage& stage, const std::string& where,
                          const std::string& source, bool long_lag) {
  using K = config::DelayStage::KindCase;
  require(stage.amplitude_gain() >= 0 && stage.amplitude_gain() <= 10, source,
          where + ".amplitude_gain must be in [0, 10] (0 means 1), got " +
              format_number(stage.amplitude_gain()));
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
    case K::kBacklash:
      require(stage.backlash().width() >= 0.0 && stage.backlash().width() <= 1.0, source,
              where + ".backlash.width must be in [0, 1] m, got " +
                  format_number(stage.backlash().width()));
      break;
    case K::kVelocityLimit:
      require(stage.velocity_limit().max_velocity() > 0.0 &&
                  stage.velocity_limit().max_velocity() <= 100.0,
              source,
              where + ".velocity_limit.max_velocity must be in (0, 100] m/s, got " +
                  format_number(stage.velocity_limit().max_velocity()));
      break;
    case K::kStrokeLimit:
      require(stage.stroke_limit().stroke() > 0.0 && stage.stroke_limit().stroke() <= 10.0, source,
              where + ".stroke_limit.stroke must be in (0, 10] m, got " +
                  format_number(stage.stroke_limit().stroke()));
      break;
    case K::kSensorDrift: {
      const auto& d = stage.sensor_drift();
      require(std::isfinite(d.displacement_offset()) && std::isfinite(d.displacement_drift()) &&
                  std::isfinite(d.force_offset()) && std::isfinite(d.force_drift()),
              source, where + ".sensor_drift: every offset and drift must be finite");
      require(d.displacement_scale() >= 0.0 && d.displacement_scale() <= 10.0, source,
              where + ".sensor_drift.displacement_scale must be in [0, 10] (0 = 1), got " +
                  format_number(d.displacement_scale()));
      break;
    }
    case K::kViscousForce:
      require(stage.viscous_force().damping() >= 0.0 && stage.viscous_force().damping() <= 1e9,
              source,
              where + ".viscous_force.damping must be in [0, 1e9] N s/m, got " +
                  format_number(stage.viscous_force().damping()));
      break;
    case K::kInertiaForce:
      require(stage.inertia_force().mass() >= 0.0 && stage.inertia_force().mass() <= 1e9, source,
              where + ".inertia_force.mass must be in [0, 1e9] kg, got " +
                  format_number(stage.inertia_force().mass()));
      break;
    case K::kFrictionForce: {
      const auto& f = stage.friction_force();
      require(f.friction_force() >= 0.0 && f.friction_force() <= 1e9, source,
              where + ".friction_force.friction_force must be in [0, 1e9] N, got " +
                  format_number(f.friction_force()));
      require(f.smoothing_velocity() > 0.0 && f.smoothing_velocity() <= 100.0, source,
              where + ".friction_force.smoothing_velocity must be in (0, 100] m/s, got " +
                  format_number(f.smoothing_velocity()));
      break;
    }
    case K::kForceDelay:
      require(stage.force_delay().delay() >= 0.0 && stage.force_delay().delay() <= 1.0, source,
              where + ".force_delay.delay must be in [0, 1] s, got " +
                  format_number(stage.force_delay().delay()));
      break;
    case K::KIND_NOT_SET: fail(source, where + " has no kind (shift, eq1, eq1_lag, ...)");
  }
}

double effective_gain(const config::DelayStage& stage) {
  return stage.amplitude_gain() == 0.0 ? 1.0 : stage.amplitude_gain();
}

}  // namespace

config::Study parse_study(const std::string& text, const std::string& source_name) {
  config::Study study;
  parse_text_format(text, source_name, study);
  validate_study(study, source_name);
  return study;
}

config::Study load_study(const std::filesystem::path& path) {
  return parse_study(read_text_file(path, "config"), path.string());
}

namespace {

void validate_structure(const config::Structure& structure, const std::string& source) {
  if (structure.has_sdof()) {
    const config::Sdof& sdof = structure.sdof();
    // Given, the mass must be one: an explicit 0 is not quietly run as 1 kg.
    require(!sdof.has_mass() || sdof.mass() > 0, source,
            "structure.sdof.mass must be > 0 kg, got " + format_number(sdof.mass()) +
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
                  "] must be > 0 kg, got " + format_number(building.storey_mass(i)));
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
  if (d.realtime_priority() != 0) {
    require_in(Quantity::kFifoPriority, d.realtime_priority(), at + "realtime_priority (0: off)",
               source);
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
  require(lag.loss() >= 0 && lag.loss() < 1, source,
          where + ".loss = " + format_number(lag.loss()) + " is outside [0, 1) (a probability)");
  validate_network_emulation(lag.network(), where + ".network", allow_long_lag, source);
}

void validate_study(const config::Study& study, const std::string& source) {
  require_known_enums(study, source);  // before anything switches over one
  require(study.has_structure(), source, "structure is missing");
  validate_structure(study.structure(), source);
  require(std::isfinite(study.servo().rate()) && study.servo().rate() >= 0, source,
          "servo.rate must be >= 0 Hz (0 = the integrator's rate), got " +
              format_number(study.servo().rate()));
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
}

namespace {

// A motion carried by a run record's header: checked as a file's would be, read from nowhere.
DelayTrace embedded_trace(const config::DelayStage::Trace& trace) {
  const std::string what = "delay trace (embedded, from '" + trace.path() + "')";
  if (trace.time_size() != trace.delay_size())
    throw std::invalid_argument(what + ": " + std::to_string(trace.time_size()) + " times but " +
                                std::to_string(trace.delay_size()) + " delays");
  DelayTrace out{{trace.time().begin(), trace.time().end()},
                 {trace.delay().begin(), trace.delay().end()}};
  for (std::size_t i = 0; i < out.time.size(); ++i) {
    if (!(out.delay[i] >= 0.0) || !std::isfinite(out.delay[i]))
      throw std::invalid_argument(what + ": sample " + std::to_string(i) + " has delay " +
                                  format_number(out.delay[i]));
    if (!std::isfinite(out.time[i]) || (i > 0 && !(out.time[i] > out.time[i - 1])))
      throw std::invalid_argument(what + ": time of sample " + std::to_string(i) +
                                  " does not increase");
  }
  return out;
}

}  // namespace

std::unique_ptr<DelayStage> make_delay_stage(const config::DelayStage& stage, double dt,
                                             const std::filesystem::path& base_dir) {
  using K = config::DelayStage::KindCase;
  std::unique_ptr<DelayStage> block;
  switch (stage.kind_case()) {
    case K::kShift: block = std::make_unique<TimeShift>(stage.shift().delay(), dt); break;
    case K::kEq1: block = std::make_unique<Eq1Lead>(stage.eq1().delay()); break;
    case K::kEq1Lag: block = std::make_unique<Eq1Lag>(stage.eq1_lag().delay()); break;
    case K::kFirstOrder:
      block = std::make_unique<FirstOrderActuator>(stage.first_order().time_constant(), dt);
      break;
    case K::kBenchmark: block = make_benchmark_actuator(dt); break;
    case K::kTransferFunction: {
      const auto& tf = stage.transfer_function();
      block = std::make_unique<TransferFunctionStage>(
          std::vector<double>(tf.numerator().begin(), tf.numerator().end()),
          std::vector<double>(tf.denominator().begin(), tf.denominator().end()), dt);
      break;
    }
    case K::kJitter:
      block = std::make_unique<JitterShift>(stage.jitter().mean_delay(), stage.jitter().std_dev(),
                                            stage.jitter().seed(), dt);
      break;
    case K::kTrace: {
      if (stage.trace().time_size() > 0) {
        block = std::make_unique<TraceShift>(embedded_trace(stage.trace()), dt);
        break;
      }
      std::filesystem::path path = stage.trace().path();
      if (path.is_relative()) path = base_dir / path;
      block = std::make_unique<TraceShift>(read_delay_trace(path), dt);
      break;
    }
    case K::kTrackingLoop:
      block = std::make_unique<TrackingLoop>(
          make_tracking_loop(stage.tracking_loop(), dt, "tracking_loop"));
      break;
    case K::kBacklash:
      block = std::make_unique<MotionLimit>(MotionLimit::backlash(stage.backlash().width()));
      break;
    case K::kVelocityLimit:
      block = std::make_unique<MotionLimit>(
          MotionLimit::velocity_limit(stage.velocity_limit().max_velocity(), dt));
      break;
    case K::kStrokeLimit:
      block =
          std::make_unique<MotionLimit>(MotionLimit::stroke_limit(stage.stroke_limit().stroke()));
      break;
    case K::kSensorDrift: {
      const auto& d = stage.sensor_drift();
      const double scale = d.displacement_scale() == 0.0 ? 1.0 : d.displacement_scale();
      block = std::make_unique<SensorDrift>(SensorErrors{d.displacement_offset(),
                                                         d.displacement_drift(), d.force_offset(),
                                                         d.force_drift(), scale});
      break;
    }
    case K::kViscousForce:
      block = std::make_unique<ViscousForce>(stage.viscous_force().damping(), dt);
      break;
    case K::kInertiaForce:
      block = std::make_unique<InertiaForce>(stage.inertia_force().mass(), dt);
      break;
    case K::kFrictionForce:
      block = std::make_unique<FrictionForce>(stage.friction_force().friction_force(),
                                              stage.friction_force().smoothing_velocity(), dt);
      break;
    case K::kForceDelay:
      block = std::make_unique<ForceDelay>(stage.force_delay().delay(), dt);
      break;
    case K::KIND_NOT_SET: throw std::invalid_argument("delay stage has no kind");
  }
  block->set_gain(effective_gain(stage));
  return block;
}

DelayChain make_delay_chain(const google::protobuf::RepeatedPtrField<config::DelayStage>& stages,
                            double dt, const std::filesystem::path& base_dir) {
  DelayChain chain;
  for (const config::DelayStage& stage : stages) chain.add(make_delay_stage(stage, dt, base_dir));
  return chain;
}

StructuralModel make_structure(const config::Structure& structure,
                               const std::filesystem::path& base_dir) {
  if (structure.has_matrices()) return matrix_structure(structure, base_dir);
  StructuralModel model;
  if (structure.has_sdof()) {
    const config::Sdof& sdof = structure.sdof();
    double mass = sdof.has_mass() ? sdof.mass() : 1.0;  // validated > 0 at load
    double stiffness = 0.0;
    if (sdof.period() > 0 && sdof.stiffness() > 0) {
      stiffness = sdof.stiffness();
      mass =
          stiffness * sdof.period() * sdof.period() / (4.0 * std::numbers::pi * std::numbers::pi);
    } else if (sdof.period() > 0) {
      const double omega = 2.0 * std::numbers::pi / sdof.period();
      stiffness = mass * omega * omega;
    } else {
      stiffness = sdof.stiffness();
    }
    model = make_shear_building({mass}, {stiffness});
  } else {
    const auto& b = structure.shear_building();
    model = make_shear_building({b.storey_mass().begin(), b.storey_mass().end()},
                                {b.storey_stiffness().begin(), b.storey_stiffness().end()});
  }
  const config::Damping& damping = structure.damping();
  if (damping.has_rayleigh()) {
    const auto& r = damping.rayleigh();
    model.damping =
        rayleigh_damping(model.mass, model.stiffness, r.zeta(), r.mode_i() == 0 ? 1 : r.mode_i(),
                         r.mode_j() == 0 ? 2 : r.mode_j());
  } else if (model.dofs() == 1) {
    // 2 zeta m omega written out, so an SDOF from a config equals make_sdof() to the last bit.
    const double omega = std::sqrt(model.stiffness(0, 0) / model.mass(0, 0));
    model.damping(0, 0) = 2.0 * damping.modal_zeta() * model.mass(0, 0) * omega;
  } else {
    model.damping = modal_damping(model.mass, model.stiffness, damping.modal_zeta());
  }
  return model;
}

namespace {
// The one map between the config's integrator kinds and core's, read both ways.
constexpr std::pair<config::Integrator::Kind, IntegratorKind> kIntegratorKinds[] = {
    {config::Integrator::EXPLICIT_NEWMARK, IntegratorKind::kExplicitNewmark},
    {config::Integrator::CENTRAL_DIFFERENCE, IntegratorKind::kCentralDifference},
    {config::Integrator::CHEN_RICLES, IntegratorKind::kChenRicles},
    {config::Integrator::NEWMARK_AVERAGE_ACCELERATION, IntegratorKind::kNewmarkAverageAcceleration},
    {config::Integrator::ALPHA_OS, IntegratorKind::kAlphaOS},
    {config::Integrator::KR_ALPHA, IntegratorKind::kKRAlpha},
    {config::Integrator::EXACT_ZOH, IntegratorKind::kExactZoh}};
}  // namespace

IntegratorKind integrator_kind(const config::Integrator& integrator) {
  for (const auto& [config_kind, kind] : kIntegratorKinds)
    if (config_kind == integrator.kind()) return kind;
  // Never a default for a value nobody chose (a study is checked at load; this is for the rest).
  std::string why = "integrator.kind ";
  why += std::to_string(integrator.kind());
  why += " is not a known integrator";
  throw std::invalid_argument(why);
}

config::Integrator::Kind config_integrator_kind(IntegratorKind kind) {
  for (const auto& [config_kind, core_kind] : kIntegratorKinds)
    if (core_kind == kind) return config_kind;
  throw std::invalid_argument("integrator " + to_string(kind) + " has no config kind");
}

int servo_substeps(const config::Study& study, double dt) {
  const double rate = study.servo().rate();
  if (rate == 0) return 1;
  const double per_step = rate * dt;
  const double whole = std::round(per_step);
  require(std::isfinite(rate) && rate > 0 && whole >= 1 && whole <= kMaxServoSubsteps &&
              std::abs(per_step - whole) <= 1e-6 * whole,
          "servo",
          "servo.rate = " + format_number(rate) + " Hz must be an integer multiple (1 to " +
              std::to_string(kMaxServoSubsteps) + ") of the integrator's rate " +
              format_number(1.0 / dt) + " Hz (dt = " + format_number(dt) + " s)");
  return static_cast<int>(whole);
}

HybridSetup base_setup(const config::Study& study, double dt, const std::filesystem::path& base_dir,
                       std::vector<std::string>* warnings) {
  HybridSetup base;
  base.model = make_structure(study.structure(), base_dir);
  base.integrator = integrator_kind(study.integrator());
  base.dt = dt;
  base.allow_unstable = study.integrator().allow_unstable();
  base.servo_substeps = servo_substeps(study, dt);
  const auto& sub = study.substructuring();
  if (study.structure().has_matrices() || !sub.experimental_dofs().empty()) {
    base.partition = split_at_dofs(base.model, sub, dt / base.servo_substeps, warnings);
    return base;
  }
  const StoreyModelFactory factory = make_storey_factory(sub.model());
  if (!sub.experimental_storeys().empty()) {
    std::vector<int> storeys;
    for (int s : sub.experimental_storeys()) storeys.push_back(s - 1);
    base.partition = partition_by_storeys(base.model.storey_stiffness, storeys, factory);
  } else {
    base.partition =
        partition_by_fraction(base.model.storey_stiffness, sub.experimental_fraction(), factory);
  }
  return base;
}

PreparedStudy prepare_study(const config::Study& study, const std::filesystem::path& base_dir) {
  PreparedStudy prepared;
  prepared.config = study;
  prepared.base_dir = base_dir;
  GroundMotion record = load_motion(study.motion(), base_dir);
  const double dt = study.integrator().dt() > 0 ? study.integrator().dt() : record.dt;
  require(dt < record.duration(), "motion",
          "integrator.dt = " + format_number(dt) + " s is not shorter than the record (" +
              format_number(record.duration()) + " s)");
  // What a run of this study keeps per step (motion, time, then per DOF and per actuator three
  // series), for a run and its reference, checked before any of it is allocated.
  prepared.base = base_setup(study, dt, base_dir, &prepared.warnings);
  const auto dofs = static_cast<std::uint64_t>(prepared.base.model.dofs());
  const auto actuators =
      static_cast<std::uint64_t>(prepared.base.partition.actuator_storeys.size());
  require_memory(static_cast<std::uint64_t>(record.duration() / dt) + 2,
                 2 * sizeof(double) * (2 + 3 * dofs + 3 * actuators),
                 "integrator.dt = " + format_number(dt) + " s over the " +
                     format_number(record.duration()) + " s record");
  prepared.motion =
      std::abs(dt - record.dt) <= 1e-12 * dt ? std::move(record) : resampled(record, dt);
  for (const config::Case& c : study.cases()) {
    const double lag = make_delay_chain(c.delay(), dt, base_dir).nominal_delay();
    require(lag < prepared.motion.duration(), "case '" + c.name() + "'",
            "its delay of " + format_number(lag) + " s is not shorter than the record (" +
                format_number(prepared.motion.duration()) + " s)");
  }
  return prepared;
}

HybridSetup setup_for_case(const PreparedStudy& prepared, const config::Case& study_case) {
  HybridSetup setup = prepared.base;
  setup.delays.clear();
  const std::size_t actuators = setup.partition.actuator_storeys.size();
  const double servo_period = setup.dt / setup.servo_substeps;
  for (std::size_t a = 0; a < actuators; ++a)
    setup.delays.push_back(make_delay_chain(study_case.delay(), servo_period, prepared.base_dir));
  std::vector<int> all(actuators);
  for (std::size_t a = 0; a < actuators; ++a) all[a] = static_cast<int>(a);
  apply_compensation(setup, all, study_case.compensation(), "case '" + study_case.name() + "'");
  if (study_case.has_force_predictor())
    apply_force_predictor(setup, study_case.force_predictor(),
                          "case '" + study_case.name() + "' force_predictor");
  return setup;
}

void validate_force_predictor(const config::ForcePredictor& block, double dt,
                              const std::string& where) {
  for (int i = 0; i < block.actuators_size(); ++i) {
    const std::string field = where + ".actuators[" + std::to_string(i) + "]";
    if (block.actuators(i) < 1)
      throw std::invalid_argument(field + " = " + std::to_string(block.actuators(i)) +
                                  " must be >= 1 (actuators are 1-based)");
    for (int j = 0; j < i; ++j)
      if (block.actuators(j) == block.actuators(i))
        throw std::invalid_argument(field + " repeats actuator " +
                                    std::to_string(block.actuators(i)));
  }
  const auto finite_at_least = [&](double value, double least, bool strict, const char* name,
                                   const std::string& unit) {
    const bool ok = std::isfinite(value) && (strict ? value > least : value >= least);
    if (!ok)
      throw std::invalid_argument(where + "." + name + " = " + format_number(value) + unit +
                                  " must be " + (strict ? "> " : ">= ") + format_number(least) +
                                  unit);
  };
  finite_at_least(block.stiffness_factor(), 0.0, false, "stiffness_factor", "");
  finite_at_least(block.damping(), 0.0, false, "damping", " N s/m");
  finite_at_least(block.forgetting_time(), 0.0, false, "forgetting_time", " s");
  finite_at_least(block.min_displacement(), 0.0, false, "min_displacement", " m");
  finite_at_least(block.error_window(), 0.0, false, "error_window", " s");
  finite_at_least(block.max_relative_error(), 0.0, false, "max_relative_error", "");
  if (block.error_window() > 0 && dt > 0 && block.error_window() < dt)
    throw std::invalid_argument(
        where + ".error_window = " + format_number(block.error_window()) +
        " s is shorter than one step (integrator.dt = " + format_number(dt) + " s)");
}

PredictorParameters predictor_parameters(const config::ForcePredictor& block,
                                         double declared_stiffness) {
  PredictorParameters p;
  p.stiffness =
      declared_stiffness * (block.stiffness_factor() > 0 ? block.stiffness_factor() : 1.0);
  p.damping = block.damping();
  p.adapt = !block.fixed_model();
  if (block.forgetting_time() > 0) p.forgetting_time = block.forgetting_time();
  if (block.min_displacement() > 0) p.min_displacement = block.min_displacement();
  if (block.error_window() > 0) p.error_window = block.error_window();
  p.max_relative_error = block.max_relative_error();
  p.specimen_shape = !block.linear_model();
  return p;
}

void apply_force_predictor(HybridSetup& setup, const config::ForcePredictor& block,
                           const std::string& where) {
  validate_force_predictor(block, setup.dt, where);
  const auto& storeys = setup.partition.actuator_storeys;
  const int actuators = static_cast<int>(storeys.size());
  std::vector<int> chosen;
  for (int a : block.actuators()) {
    if (a > actuators)
      throw std::invalid_argument(where + ".actuators names actuator " + std::to_string(a) +
                                  " but the study has " + std::to_string(actuators));
    chosen.push_back(a - 1);
  }
  if (chosen.empty())
    for (int a = 0; a < actuators; ++a) chosen.push_back(a);
  setup.predictors.assign(static_cast<std::size_t>(actuators), std::nullopt);
  for (int a : chosen) {
    const auto& specimen =
        setup.partition
            .experimental[static_cast<std::size_t>(storeys[static_cast<std::size_t>(a)])];
    if (!specimen)
      throw std::invalid_argument(where + ": actuator " + std::to_string(a + 1) +
                                  " has no declared specimen to start its model from");
    PredictorParameters p = predictor_parameters(block, specimen->initial_stiffness());
    // Built once here so that a parameter out of range is refused before any run, named.
    ForcePredictor check(p, setup.dt, where + " (actuator " + std::to_string(a + 1) + ")",
                         specimen.get());
    setup.predictors[static_cast<std::size_t>(a)] = p;
  }
}

void apply_compensation(HybridSetup& setup, const std::vector<int>& actuators,
                        const google::protobuf::RepeatedPtrField<config::Compensation>& blocks,
                        const std::string& where) {
  if (blocks.empty()) return;
  const auto count = static_cast<std::size_t>(blocks.size());
  if (count > 1 && count != actuators.size()) {
    throw std::invalid_argument(where + ": " + std::to_string(count) + " compensation blocks for " +
                                std::to_string(actuators.size()) +
                                " actuators; give one (for every actuator) or one per actuator");
  }
  const double servo_period = setup.dt / setup.servo_substeps;
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    const int a = actuators[i];
    if (a < 0 || a >= static_cast<int>(setup.delays.size()))
      throw std::invalid_argument(where + ": actuator " + std::to_string(a + 1) +
                                  " does not exist");
    const std::size_t b = count == 1 ? 0 : i;
    const std::string block_name = where + " compensation[" + std::to_string(b) + "]";
    if (setup.delays[static_cast<std::size_t>(a)].compensator())
      throw std::invalid_argument(
          block_name + ": actuator " + std::to_string(a + 1) +
          " already has a compensator (from its case); give it in one place");
    setup.delays[static_cast<std::size_t>(a)].set_compensator(
        make_compensator(blocks[static_cast<int>(b)], servo_period, block_name));
  }
}

const config::Case& reference_case(const config::Study& study) {
  if (study.cases_size() == 0) throw std::invalid_argument("the study has no cases");
  if (!study.reference_case().empty()) {
    for (const config::Case& c : study.cases()) {
      if (c.name() == study.reference_case()) return c;
    }
    throw std::invalid_argument("reference_case '" + study.reference_case() +
                                "' is not among the cases");
  }
  return study.cases(0);
}

const config::Case* case_named(const config::Study& study, const std::string& name) {
  if (name.empty()) return &reference_case(study);
  for (const config::Case& c : study.cases())
    if (c.name() == name) return &c;
  return nullptr;
}

const config::Case& find_case(const config::Study& study, const std::string& name) {
  if (const config::Case* c = case_named(study, name)) return *c;
  throw std::invalid_argument("case '" + name + "' is not among the study's cases");
}

}  // namespace rths::core
