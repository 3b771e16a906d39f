#pragma once
// A study's ground motion (config::GroundMotion) as read: embedded in a record's inputs or from
// its file (resolved against base_dir, checked against its sha256 pin, refused by its size before
// it is read: require_motion_file_size, study/motion_files.h), in SI units, and the names of its
// units.

#include <filesystem>
#include <optional>
#include <string>

#include "core/ground_motion.h"
#include "rths/proto/config.pb.h"
#include "study/motion_files.h"

namespace rths::study {

inline constexpr double kMaxPeakGroundAcceleration =
    5.0 * core::kGravity;  // m/s^2; recorded peaks stay under 4 g

// Reads the record in SI, with its read_units and description (core/ground_motion.h). An AT2
// file is read in the units its header states (at2_stated_units, study/motion_files.h), else
// column_units, else g. Throws std::invalid_argument when a columns file has no column_units, an
// AT2 header and column_units disagree (naming both), or the peak exceeds
// kMaxPeakGroundAcceleration (a record in cm/s^2 read as g or m/s^2).
core::GroundMotion load_motion(const config::GroundMotion& motion,
                               const std::filesystem::path& base_dir);
// The record's extent from its file before a sample is parsed (motion_file_extent: a lower
// bound on its samples, at most what motion.duration keeps), for sizing the run first. Empty
// for an embedded motion or a column file without column_dt. Throws as load_motion does on a
// file that is missing, too large, not text, or a malformed AT2 header.
std::optional<MotionFileExtent> motion_extent_before_reading(const config::GroundMotion& motion,
                                                             const std::filesystem::path& base_dir);
// "g", "m/s2", "cm/s2", "in/s2" or "mm/s2": what a record in these units is called on the
// command line and in summaries.
std::string units_name(config::GroundMotion::Units units);
// m/s^2 per unit.
double units_to_si(config::GroundMotion::Units units);
// Parses those names (also "m/s^2", "cm/s^2", "gal", ...); throws naming the accepted forms.
config::GroundMotion::Units units_from_name(const std::string& name);
// The units the config names: its column_units, or g (a loaded record's read_units is what was
// used).
std::string motion_units_name(const config::GroundMotion& motion);

}  // namespace rths::study
