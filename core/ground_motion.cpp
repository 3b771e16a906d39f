#include "core/ground_motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rths::core {

double GroundMotion::peak_abs() const {
  double peak = 0.0;
  for (double a : acceleration) {
    if (std::isnan(a)) return a;
    peak = std::max(peak, std::abs(a));
  }
  return peak;
}

GroundMotion scaled(GroundMotion motion, double factor) {
  if (!std::isfinite(factor)) {
    throw std::invalid_argument("scaled: factor for '" + motion.name + "' must be finite");
  }
  for (double& a : motion.acceleration) a *= factor;
  return motion;
}

GroundMotion resampled(const GroundMotion& motion, double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument("resampled: dt for '" + motion.name + "' must be > 0, got " +
                                std::to_string(dt));
  }
  GroundMotion out;
  out.name = motion.name;
  out.read_units = motion.read_units;
  out.description = motion.description;
  out.dt = dt;
  const std::size_t n = motion.acceleration.size();
  if (n == 0) return out;
  // Samples j with j dt < duration; the 1e-9 keeps an exact ratio (39.07 s / 1 ms) from
  // gaining a sample to round-off.
  const double ratio = motion.duration() / dt;
  const auto count = static_cast<std::size_t>(std::ceil(ratio - 1e-9 * std::max(1.0, ratio)));
  out.acceleration.resize(std::max<std::size_t>(count, 1));
  for (std::size_t j = 0; j < out.acceleration.size(); ++j) {
    const double position = static_cast<double>(j) * dt / motion.dt;  // in source samples
    const auto i = static_cast<std::size_t>(position);
    if (i + 1 >= n) {
      out.acceleration[j] = motion.acceleration[n - 1];
    } else {
      const double w = position - static_cast<double>(i);
      out.acceleration[j] =
          motion.acceleration[i] + w * (motion.acceleration[i + 1] - motion.acceleration[i]);
    }
  }
  return out;
}

GroundMotion truncated(GroundMotion motion, double duration) {
  if (duration <= 0.0 || duration >= motion.duration()) return motion;
  const double ratio = duration / motion.dt;
  const auto keep = static_cast<std::size_t>(std::ceil(ratio - 1e-9 * std::max(1.0, ratio)));
  motion.acceleration.resize(std::max<std::size_t>(keep, 1));
  return motion;
}

}  // namespace rths::core
