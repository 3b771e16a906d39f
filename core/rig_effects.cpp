#include "core/rig_effects.h"

#include <algorithm>
#include <cmath>

#include "core/number_text.h"
#include "core/precondition.h"

namespace rths::core {

MotionLimit::MotionLimit(Kind kind, double limit, double reach)
    : kind_(kind), limit_(limit), reach_(reach) {}

MotionLimit MotionLimit::backlash(double width) {
  require(width >= 0.0 && std::isfinite(width),
          "backlash: width must be >= 0 m, got " + format_number(width));
  return MotionLimit(Kind::kBacklash, width, 0.5 * width);
}

MotionLimit MotionLimit::velocity_limit(double max_velocity, double dt) {
  require(max_velocity > 0.0 && std::isfinite(max_velocity),
          "velocity_limit: max_velocity must be > 0 m/s, got " + format_number(max_velocity));
  require(dt > 0.0 && std::isfinite(dt), "velocity_limit: dt must be > 0 s");
  return MotionLimit(Kind::kVelocityLimit, max_velocity, max_velocity * dt);
}

MotionLimit MotionLimit::stroke_limit(double stroke) {
  require(stroke > 0.0 && std::isfinite(stroke),
          "stroke_limit: stroke must be > 0 m, got " + format_number(stroke));
  return MotionLimit(Kind::kStrokeLimit, stroke, stroke);
}

std::unique_ptr<DelayStage> MotionLimit::clone() const {
  return std::make_unique<MotionLimit>(*this);
}

std::string MotionLimit::describe() const {
  switch (kind_) {
    case Kind::kBacklash: return "backlash(width " + format_number(limit_ * 1e3) + " mm)";
    case Kind::kVelocityLimit: return "velocity_limit(" + format_number(limit_ * 1e3) + " mm/s)";
    case Kind::kStrokeLimit: return "stroke_limit(+-" + format_number(limit_ * 1e3) + " mm)";
  }
  return {};
}

Linearity MotionLimit::linearity() const {
  switch (kind_) {
    case Kind::kBacklash:
      return {Linearity::Kind::kLinearised, "backlash left out (a small motion passes unchanged)"};
    case Kind::kVelocityLimit:
      return {Linearity::Kind::kLinearised,
              "velocity limit left out (below it motion is unchanged)"};
    case Kind::kStrokeLimit:
      return {Linearity::Kind::kLinearised,
              "stroke limit left out (inside the stroke motion is unchanged)"};
  }
  return {};
}

double MotionLimit::step_unscaled(const CommandSample& in) {
  switch (kind_) {
    case Kind::kBacklash:
      output_ = std::clamp(output_, in.displacement - reach_, in.displacement + reach_);
      break;
    case Kind::kVelocityLimit:
      output_ += std::clamp(in.displacement - output_, -reach_, reach_);
      break;
    case Kind::kStrokeLimit: output_ = std::clamp(in.displacement, -reach_, reach_); break;
  }
  return output_;
}

SensorDrift::SensorDrift(const SensorErrors& errors) : errors_(errors) {
  require(errors.displacement_scale > 0.0 && std::isfinite(errors.displacement_scale),
          "sensor_drift: displacement_scale must be > 0 and finite");
  const std::pair<const char*, double> fields[] = {
      {"displacement_offset", errors.displacement_offset},
      {"displacement_drift", errors.displacement_drift},
      {"force_offset", errors.force_offset},
      {"force_drift", errors.force_drift}};
  for (const auto& [name, value] : fields)
    require(std::isfinite(value), std::string("sensor_drift: ") + name + " must be finite");
}

std::unique_ptr<DelayStage> SensorDrift::clone() const {
  return std::make_unique<SensorDrift>(*this);
}

std::string SensorDrift::describe() const {
  return "sensor_drift(displacement " + format_number(errors_.displacement_scale) + " u + " +
         format_number(errors_.displacement_offset * 1e3) + " mm + " +
         format_number(errors_.displacement_drift * 1e3) + " mm/s t, force " +
         format_number(errors_.force_offset) + " N + " + format_number(errors_.force_drift) +
         " N/s t)";
}

ViscousForce::ViscousForce(double damping, double dt) : damping_(damping), dt_(dt) {
  require(std::isfinite(damping) && damping >= 0.0,
          "viscous_force: damping must be >= 0 N s/m and finite");
  require(dt > 0.0, "viscous_force: dt must be > 0 s");
}

std::unique_ptr<DelayStage> ViscousForce::clone() const {
  return std::make_unique<ViscousForce>(*this);
}

std::string ViscousForce::describe() const {
  return "viscous_force(" + format_number(damping_) + " N s/m)";
}

InertiaForce::InertiaForce(double mass, double dt) : mass_(mass), dt_(dt) {
  require(std::isfinite(mass) && mass >= 0.0,
          "inertia_force: mass must be >= 0 kg and finite, got " + format_number(mass));
  require(dt > 0.0 && std::isfinite(dt), "inertia_force: dt must be > 0 s");
}

std::unique_ptr<DelayStage> InertiaForce::clone() const {
  return std::make_unique<InertiaForce>(*this);
}

std::string InertiaForce::describe() const {
  return "inertia_force(" + format_number(mass_) + " kg)";
}

FrictionForce::FrictionForce(double friction_force, double smoothing_velocity, double dt)
    : friction_force_(friction_force), smoothing_velocity_(smoothing_velocity), dt_(dt) {
  require(std::isfinite(friction_force) && friction_force >= 0.0,
          "friction_force: friction_force must be >= 0 N and finite, got " +
              format_number(friction_force));
  require(std::isfinite(smoothing_velocity) && smoothing_velocity > 0.0,
          "friction_force: smoothing_velocity must be > 0 m/s and finite, got " +
              format_number(smoothing_velocity));
  require(dt > 0.0 && std::isfinite(dt), "friction_force: dt must be > 0 s");
}

std::unique_ptr<DelayStage> FrictionForce::clone() const {
  return std::make_unique<FrictionForce>(*this);
}

std::string FrictionForce::describe() const {
  return "friction_force(" + format_number(friction_force_) + " N, smoothing " +
         format_number(smoothing_velocity_ * 1e3) + " mm/s)";
}

ForceDelay::ForceDelay(double delay, double dt)
    : delay_((require(std::isfinite(delay) && delay >= 0.0,
                      "force_delay: delay must be >= 0 s and finite, got " + format_number(delay)),
              delay)),
      forces_(delay, dt) {}

std::unique_ptr<DelayStage> ForceDelay::clone() const {
  return std::make_unique<ForceDelay>(*this);
}

std::string ForceDelay::describe() const {
  return "force_delay(" + format_number(delay_ * 1e3) + " ms)";
}

}  // namespace rths::core
