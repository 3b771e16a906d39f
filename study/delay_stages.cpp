#include "study/study.h"

#include "core/number_text.h"
#include "core/rig_effects.h"
#include "study/delay_trace_file.h"
#include "study/tracking_config.h"

#include <cmath>
#include <stdexcept>
#include <string>

// make_delay_stage and make_delay_chain: the blocks of rths_core a validated study's delay
// stages name, each at its amplitude gain.
namespace rths::study {
namespace {

double effective_gain(const config::DelayStage& stage) {
  return stage.amplitude_gain() == 0.0 ? 1.0 : stage.amplitude_gain();
}

// A motion carried by a run record's header: checked as a file's would be, read from nowhere.
core::DelayTrace embedded_trace(const config::DelayStage::Trace& trace) {
  const std::string what = "delay trace (embedded, from '" + trace.path() + "')";
  if (trace.time_size() != trace.delay_size())
    throw std::invalid_argument(what + ": " + std::to_string(trace.time_size()) + " times but " +
                                std::to_string(trace.delay_size()) + " delays");
  core::DelayTrace out{{trace.time().begin(), trace.time().end()},
                       {trace.delay().begin(), trace.delay().end()}};
  for (std::size_t i = 0; i < out.time.size(); ++i) {
    if (!(out.delay[i] >= 0.0) || !std::isfinite(out.delay[i]))
      throw std::invalid_argument(what + ": sample " + std::to_string(i) + " has delay " +
                                  core::format_number(out.delay[i]));
    if (!std::isfinite(out.time[i]) || (i > 0 && !(out.time[i] > out.time[i - 1])))
      throw std::invalid_argument(what + ": time of sample " + std::to_string(i) +
                                  " does not increase");
  }
  return out;
}

// The stages that model a rig's effects (core/rig_effects.h): motion limits, sensor errors and
// the specimen's parasitic forces; null for any other kind.
std::unique_ptr<core::DelayStage> make_rig_effect(const config::DelayStage& stage, double dt) {
  using K = config::DelayStage::KindCase;
  std::unique_ptr<core::DelayStage> block;
  switch (stage.kind_case()) {
    case K::kBacklash:
      block = std::make_unique<core::MotionLimit>(
          core::MotionLimit::backlash(stage.backlash().width()));
      break;
    case K::kVelocityLimit:
      block = std::make_unique<core::MotionLimit>(
          core::MotionLimit::velocity_limit(stage.velocity_limit().max_velocity(), dt));
      break;
    case K::kStrokeLimit:
      block = std::make_unique<core::MotionLimit>(
          core::MotionLimit::stroke_limit(stage.stroke_limit().stroke()));
      break;
    case K::kSensorDrift: {
      const auto& d = stage.sensor_drift();
      const double scale = d.displacement_scale() == 0.0 ? 1.0 : d.displacement_scale();
      block = std::make_unique<core::SensorDrift>(
          core::SensorErrors{d.displacement_offset(), d.displacement_drift(), d.force_offset(),
                             d.force_drift(), scale});
      break;
    }
    case K::kViscousForce:
      block = std::make_unique<core::ViscousForce>(stage.viscous_force().damping(), dt);
      break;
    case K::kInertiaForce:
      block = std::make_unique<core::InertiaForce>(stage.inertia_force().mass(), dt);
      break;
    case K::kFrictionForce:
      block = std::make_unique<core::FrictionForce>(
          stage.friction_force().friction_force(), stage.friction_force().smoothing_velocity(), dt);
      break;
    case K::kForceDelay:
      block = std::make_unique<core::ForceDelay>(stage.force_delay().delay(), dt);
      break;
    default: break;
  }
  return block;
}

}  // namespace

std::unique_ptr<core::DelayStage> make_delay_stage(const config::DelayStage& stage, double dt,
                                                   const std::filesystem::path& base_dir) {
  using K = config::DelayStage::KindCase;
  std::unique_ptr<core::DelayStage> block;
  switch (stage.kind_case()) {
    case K::kShift: block = std::make_unique<core::TimeShift>(stage.shift().delay(), dt); break;
    case K::kEq1: block = std::make_unique<core::Eq1Lead>(stage.eq1().delay()); break;
    case K::kEq1Lag: block = std::make_unique<core::Eq1Lag>(stage.eq1_lag().delay()); break;
    case K::kFirstOrder:
      block = std::make_unique<core::FirstOrderActuator>(stage.first_order().time_constant(), dt);
      break;
    case K::kBenchmark: block = core::make_benchmark_actuator(dt); break;
    case K::kTransferFunction: {
      const auto& tf = stage.transfer_function();
      block = std::make_unique<core::TransferFunctionStage>(
          std::vector<double>(tf.numerator().begin(), tf.numerator().end()),
          std::vector<double>(tf.denominator().begin(), tf.denominator().end()), dt);
      break;
    }
    case K::kJitter:
      block = std::make_unique<core::JitterShift>(
          stage.jitter().mean_delay(), stage.jitter().std_dev(), stage.jitter().seed(), dt);
      break;
    case K::kTrace: {
      if (stage.trace().time_size() > 0) {
        block = std::make_unique<core::TraceShift>(embedded_trace(stage.trace()), dt);
        break;
      }
      std::filesystem::path path = stage.trace().path();
      if (path.is_relative()) path = base_dir / path;
      block = std::make_unique<core::TraceShift>(read_delay_trace(path), dt);
      break;
    }
    case K::kTrackingLoop:
      block = std::make_unique<core::TrackingLoop>(
          make_tracking_loop(stage.tracking_loop(), dt, "tracking_loop"));
      break;
    case K::kBacklash:
    case K::kVelocityLimit:
    case K::kStrokeLimit:
    case K::kSensorDrift:
    case K::kViscousForce:
    case K::kInertiaForce:
    case K::kFrictionForce:
    case K::kForceDelay: block = make_rig_effect(stage, dt); break;
    case K::KIND_NOT_SET: throw std::invalid_argument("delay stage has no kind");
  }
  block->set_gain(effective_gain(stage));
  return block;
}

core::DelayChain make_delay_chain(
    const google::protobuf::RepeatedPtrField<config::DelayStage>& stages, double dt,
    const std::filesystem::path& base_dir) {
  core::DelayChain chain;
  for (const config::DelayStage& stage : stages) chain.add(make_delay_stage(stage, dt, base_dir));
  return chain;
}

}  // namespace rths::study
