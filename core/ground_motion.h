#pragma once
// Ground-motion records as signals: scaling, truncation and linear resampling to the integration
// step (the file readers are study/motion_files.h).
//
// Output units: time in s, acceleration in m/s^2 (AT2 values, in g, are multiplied by kGravity).

#include <string>
#include <vector>

namespace rths::core {

inline constexpr double kGravity = 9.80665;  // m/s^2, standard gravity

struct GroundMotion {
  std::string name;                  // file stem or header title
  double dt = 0.0;                   // s, uniform sample spacing
  std::vector<double> acceleration;  // m/s^2, sample i at time i * dt
  // As read, for reports (empty when made in code): the units its values were in ("g", "cm/s2",
  // ...) and one line on the record as read: points, step, duration, PGA, where its units came
  // from. Scaling, truncation and resampling keep both.
  std::string read_units{};
  std::string description{};

  double duration() const { return dt * static_cast<double>(acceleration.size()); }
  double peak_abs() const;
};

// Multiplies every sample by `factor`.
GroundMotion scaled(GroundMotion motion, double factor);

// Linear interpolation onto a grid of step `dt` covering the same duration. Samples past the last
// record value are held at the last value only up to the record's duration.
// @pre dt > 0.
GroundMotion resampled(const GroundMotion& motion, double dt);

// Truncates to the first `duration` seconds (no-op if duration <= 0 or longer than the record).
GroundMotion truncated(GroundMotion motion, double duration);

}  // namespace rths::core
