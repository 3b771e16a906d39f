#include "study/motion_config.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/number_text.h"
#include "study/motion_files.h"
#include "study/text_columns.h"
#include "util/sha256.h"

namespace rths::study {
namespace {

core::GroundMotion embedded_motion(const config::EmbeddedMotion& embedded) {
  const std::string what = "motion.embedded ('" + embedded.name() + "')";
  if (!(embedded.dt() > 0.0) || !std::isfinite(embedded.dt()))
    throw std::invalid_argument(what + ": dt = " + core::format_number(embedded.dt()) +
                                " s is not a positive step");
  if (embedded.acceleration_size() == 0) throw std::invalid_argument(what + ": no samples");
  core::GroundMotion record{embedded.name(),
                            embedded.dt(),
                            {embedded.acceleration().begin(), embedded.acceleration().end()}};
  for (std::size_t i = 0; i < record.acceleration.size(); ++i)
    if (!std::isfinite(record.acceleration[i]))
      throw std::invalid_argument(what + ": sample " + std::to_string(i) + " is not finite");
  if (!(record.peak_abs() <= kMaxPeakGroundAcceleration))
    throw std::invalid_argument(what + ": peak " + core::format_number(record.peak_abs()) +
                                " m/s^2 is beyond any recorded earthquake");
  return record;
}

void check_sha256(const std::filesystem::path& path, const std::string& expected) {
  const std::string actual = util::file_sha256(path);
  if (actual != expected)
    throw std::invalid_argument("motion '" + path.string() + "': sha256 " + actual + ", expected " +
                                expected +
                                " (motion.sha256): the file is not the record the study names");
}

// A delay trace carried by a run record's header, held to read_delay_trace's rules.

}  // namespace

std::string units_name(config::GroundMotion::Units units) {
  switch (units) {
    case config::GroundMotion::M_PER_S2: return "m/s2";
    case config::GroundMotion::CM_PER_S2: return "cm/s2";
    case config::GroundMotion::IN_PER_S2: return "in/s2";
    case config::GroundMotion::MM_PER_S2: return "mm/s2";
    default: return "g";
  }
}

double units_to_si(config::GroundMotion::Units units) {
  switch (units) {
    case config::GroundMotion::M_PER_S2: return 1.0;
    case config::GroundMotion::CM_PER_S2: return 0.01;
    case config::GroundMotion::IN_PER_S2: return 0.0254;
    case config::GroundMotion::MM_PER_S2: return 0.001;
    default: return core::kGravity;
  }
}

config::GroundMotion::Units units_from_name(const std::string& name) {
  if (name == "g") return config::GroundMotion::G;
  if (name == "m/s2" || name == "m/s^2") return config::GroundMotion::M_PER_S2;
  if (name == "cm/s2" || name == "cm/s^2" || name == "gal") return config::GroundMotion::CM_PER_S2;
  if (name == "in/s2" || name == "in/s^2") return config::GroundMotion::IN_PER_S2;
  if (name == "mm/s2" || name == "mm/s^2") return config::GroundMotion::MM_PER_S2;
  throw std::invalid_argument("unknown motion units '" + name +
                              "': use g, m/s2, cm/s2, in/s2 or mm/s2");
}

std::string motion_units_name(const config::GroundMotion& motion) {
  return motion.has_column_units() ? units_name(motion.column_units()) : "g";
}

namespace {

// The units an AT2 file is read in: its header's, else the config's, else g by the format; a
// header and a config that disagree are refused naming both.
struct ReadUnits {
  std::string name;
  double to_si = core::kGravity;
  std::string source;
};

ReadUnits at2_units(const config::GroundMotion& motion, const std::filesystem::path& path,
                    const std::string& what) {
  const std::optional<StatedUnits> stated = at2_stated_units(path);
  if (stated) {
    if (motion.has_column_units() && units_name(motion.column_units()) != stated->name)
      throw std::invalid_argument(what + ": its AT2 header states " + stated->name + " ('" +
                                  stated->line + "') but motion.column_units (--motion-units) " +
                                  "says " + units_name(motion.column_units()) +
                                  "; drop one or make them agree");
    return {stated->name, stated->to_si, "the AT2 header: '" + stated->line + "'"};
  }
  if (motion.has_column_units())
    return {units_name(motion.column_units()), units_to_si(motion.column_units()),
            "motion.column_units; the AT2 header states none"};
  return {"g", core::kGravity, "the AT2 format; its header states none"};
}

ReadUnits column_units(const config::GroundMotion& motion, const std::string& what) {
  if (!motion.has_column_units())
    throw std::invalid_argument(
        what +
        " is a columns file, whose numbers carry no unit: give "
        "motion.column_units (G, M_PER_S2, CM_PER_S2, IN_PER_S2 or MM_PER_S2; --motion-units "
        "g|m/s2|cm/s2|in/s2|mm/s2)");
  return {units_name(motion.column_units()), units_to_si(motion.column_units()),
          "motion.column_units"};
}

std::string describe_read(const core::GroundMotion& record, const ReadUnits& units) {
  std::ostringstream out;
  out << std::setprecision(4) << record.acceleration.size() << " points at dt " << record.dt
      << " s (" << record.duration() << " s), PGA " << record.peak_abs() / units.to_si << " "
      << units.name;
  if (units.name != "g") out << " = " << record.peak_abs() / core::kGravity << " g";
  out << "; values in " << units.name << " (" << units.source << ")";
  return out.str();
}

// The motion's file, against base_dir when relative, sized and checked for text before it is
// scanned, hashed or read (study/motion_files.h).
std::filesystem::path checked_motion_path(const config::GroundMotion& motion,
                                          const std::filesystem::path& base_dir) {
  if (motion.path().empty()) throw std::invalid_argument("motion.path is empty");
  std::filesystem::path path = motion.path();
  if (path.is_relative()) path = base_dir / path;
  require_motion_file_size(path);
  if (const std::string why = not_a_text_file(path, "ground-motion file"); !why.empty())
    throw std::invalid_argument("motion: " + why);
  return path;
}

}  // namespace

std::optional<MotionFileExtent> motion_extent_before_reading(
    const config::GroundMotion& motion, const std::filesystem::path& base_dir) {
  if (motion.has_embedded()) return std::nullopt;
  const std::filesystem::path path = checked_motion_path(motion, base_dir);
  const bool at2 = motion.format() == config::GroundMotion::AT2 ||
                   (motion.format() == config::GroundMotion::AUTO && is_at2_file(path));
  std::optional<MotionFileExtent> extent = motion_file_extent(path, at2, motion.column_dt());
  if (extent && motion.duration() > 0) {  // the samples truncated() keeps, at most
    const double kept = std::ceil(motion.duration() / extent->dt);
    if (kept < static_cast<double>(extent->samples))
      extent->samples = static_cast<std::uint64_t>(kept);
  }
  return extent;
}

core::GroundMotion load_motion(const config::GroundMotion& motion,
                               const std::filesystem::path& base_dir) {
  if (motion.has_embedded()) return embedded_motion(motion.embedded());
  const std::filesystem::path path = checked_motion_path(motion, base_dir);
  if (!motion.sha256().empty()) check_sha256(path, motion.sha256());
  bool at2 = motion.format() == config::GroundMotion::AT2;
  if (motion.format() == config::GroundMotion::AUTO) at2 = is_at2_file(path);
  const std::string what = "motion '" + path.string() + "'";
  const ReadUnits units = at2 ? at2_units(motion, path, what) : column_units(motion, what);
  core::GroundMotion record =
      at2 ? read_at2(path, units.to_si) : read_columns(path, motion.column_dt(), units.to_si);
  const double peak = record.peak_abs();
  if (!(peak <= kMaxPeakGroundAcceleration)) {
    std::ostringstream message;
    message << what << ": peak acceleration " << peak / core::kGravity << " g read as "
            << units.name << " (" << units.source
            << ") is beyond any recorded earthquake (under 4 g); are the units right "
               "(motion.column_units, --motion-units)?";
    throw std::invalid_argument(message.str());
  }
  record.read_units = units.name;
  record.description = describe_read(record, units);
  if (motion.scale() < 0) throw std::invalid_argument("motion.scale must be >= 0");
  if (motion.scale() > 0 && motion.scale() != 1.0)
    record = core::scaled(std::move(record), motion.scale());
  if (motion.duration() > 0 && motion.duration() < record.duration())
    record.description += "; the first " + core::format_number(motion.duration()) + " s used";
  return core::truncated(std::move(record), motion.duration());
}

}  // namespace rths::study
