#pragma once
// A study's ground motion (config::GroundMotion) as read: embedded in a record's inputs or from
// its file (resolved against base_dir, checked against its sha256 pin, refused by its size before
// it is read: require_motion_file_size, study/motion_files.h), in SI units, and the names of its
// units.

#include <filesystem>
#include <string>

#include "core/ground_motion.h"
#include "rths/proto/config.pb.h"

namespace rths::core {

inline constexpr double kMaxPeakGroundAcceleration =
    5.0 * kGravity;  // m/s^2; recorded peaks stay under 4 g

// Reads the record in SI. Throws std::invalid_argument when a columns file has no column_units,
// an AT2 file is given a unit other than G, or the peak exceeds kMaxPeakGroundAcceleration (a
// record in cm/s^2 read as g or m/s^2).
GroundMotion load_motion(const config::GroundMotion& motion, const std::filesystem::path& base_dir);
// "g", "m/s2" or "cm/s2": what a record in these units is called on the command line and in
// summaries.
std::string units_name(config::GroundMotion::Units units);
// Parses "g", "m/s2" or "cm/s2" (also "m/s^2", "cm/s^2"); throws naming the accepted forms.
config::GroundMotion::Units units_from_name(const std::string& name);
// The units of the study's record as read: its column_units, or g for an AT2 file.
std::string motion_units_name(const config::GroundMotion& motion);

}  // namespace rths::core
