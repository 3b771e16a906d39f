#include "core/rig_effects.h"

#include <algorithm>
#include <cmath>

#include "core/number_text.h"
#include "core/precondition.h"

namespace rths::core {

Backlash::Backlash(double width) : half_width_(0.5 * width) {
  require(width >= 0.0 && std::isfinite(width),
          "backlash: width must be >= 0 m, got " + format_number(width));
}

std::unique_ptr<DelayStage> Backlash::clone() const { return std::make_unique<Backlash>(*this); }

std::string Backlash::describe() const {
  return "backlash(width " + format_number(2.0 * half_width_ * 1e3) + " mm)";
}

Linearity Backlash::linearity() const {
  return {Linearity::Kind::kLinearised, "backlash left out (a small motion passes unchanged)"};
}

double Backlash::step_unscaled(const CommandSample& in) {
  output_ = std::clamp(output_, in.displacement - half_width_, in.displacement + half_width_);
  return output_;
}

VelocityLimit::VelocityLimit(double max_velocity, double dt)
    : max_velocity_(max_velocity), max_step_(max_velocity * dt) {
  require(max_velocity > 0.0 && std::isfinite(max_velocity),
          "velocity_limit: max_velocity must be > 0 m/s, got " + format_number(max_velocity));
  require(dt > 0.0 && std::isfinite(dt), "velocity_limit: dt must be > 0 s");
}

std::unique_ptr<DelayStage> VelocityLimit::clone() const {
  return std::make_unique<VelocityLimit>(*this);
}

std::string VelocityLimit::describe() const {
  return "velocity_limit(" + format_number(max_velocity_ * 1e3) + " mm/s)";
}

Linearity VelocityLimit::linearity() const {
  return {Linearity::Kind::kLinearised, "velocity limit left out (below it motion is unchanged)"};
}

double VelocityLimit::step_unscaled(const CommandSample& in) {
  output_ += std::clamp(in.displacement - output_, -max_step_, max_step_);
  return output_;
}

SensorDrift::SensorDrift(const SensorErrors& errors) : errors_(errors) {
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
  return "sensor_drift(displacement " + format_number(errors_.displacement_offset * 1e3) +
         " mm + " + format_number(errors_.displacement_drift * 1e3) + " mm/s t, force " +
         format_number(errors_.force_offset) + " N + " + format_number(errors_.force_drift) +
         " N/s t)";
}

}  // namespace rths::core
