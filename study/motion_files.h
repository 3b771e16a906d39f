#pragma once
// Ground-motion files: readers for PEER AT2 (both dialects seen in the wild) and plain column
// text, into core::GroundMotion (time in s, acceleration in m/s^2; AT2 values, in g, are
// multiplied by kGravity).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "core/ground_motion.h"

namespace rths::study {

// Reading a motion file holds at most kMotionReadBytesPerFileByte bytes of memory per byte of
// file: read_text_columns' worst case (one-character samples, "1\n", an object per line, 48.1
// at its peak), a bound for every reader; read_columns streams the lines (for_each_text_row) and
// keeps the samples only. Every reader below sizes the file before it reads a byte of it
// (stat), and refuses one over motion_file_limit_bytes(): kMaxMotionFileBytes, or less when the
// memory budget (memory_limit_bytes(), study/memory_budget.h) cannot hold the reading of a file
// that large at kMotionReadBytesPerFileByte. 128 MiB of text is 5 million two-column samples of
// 25 bytes: 1.5 hours at 1 kHz, beyond any earthquake record.
inline constexpr std::uintmax_t kMaxMotionFileBytes = 128ull << 20;
inline constexpr std::uintmax_t kMotionReadBytesPerFileByte = 50;

// min(kMaxMotionFileBytes, memory_limit_bytes() / kMotionReadBytesPerFileByte), in bytes.
std::uintmax_t motion_file_limit_bytes();

// Throws std::invalid_argument naming the file, its size and the limit (and what sets it) when
// `path` is a regular file larger than motion_file_limit_bytes(); a file that is not there, or
// not a regular file, is left to the reader's own refusal. Reads nothing of the file.
void require_motion_file_size(const std::filesystem::path& path);

// A motion file's extent before a sample of it is parsed, so that a run too long for the memory
// budget is refused in the time it takes to scan the bytes, not to parse them. `samples` is a
// lower bound on what the reader finds: an AT2 header's NPTS (the reader refuses any other
// count), or a column file's lines holding anything but field separators (study/text_columns.h)
// and not starting with '#', less one (a title line, which the reader skips). `dt` (s): the AT2
// header's DT, or the given column_dt.
struct MotionFileExtent {
  std::uint64_t samples = 0;
  double dt = 0.0;  // s
  double seconds() const { return dt * static_cast<double>(samples); }
};
// Sizes the file first (require_motion_file_size). A column file scanned as bytes in 1 MiB
// blocks, holding nothing else. Empty for a column file with column_dt 0 (its dt is in its
// times, known once two rows are parsed). Throws std::invalid_argument on a malformed AT2 header
// (as read_at2), a file that cannot be opened, or a column_dt that is negative, not a number, or
// so large that dt x samples is not finite (naming motion.column_dt).
std::optional<MotionFileExtent> motion_file_extent(const std::filesystem::path& path, bool at2,
                                                   double column_dt);

// Each reader first calls require_motion_file_size.

// Reads a PEER AT2 file: 4 header lines, the 4th holding NPTS and DT in either of the forms
// "NPTS=  1559, DT=   .0200 SEC" or "7814    0.0050    NPTS, DT", then values in any
// whitespace-separated layout (8F10.5, 5E15.7, ...), each multiplied by `to_si` (the units'
// m/s^2; g by the format). Throws std::invalid_argument (bad input) naming the file and line when
// the header is malformed, a value does not parse, or fewer or more than NPTS values are found.
core::GroundMotion read_at2(const std::filesystem::path& path, double to_si = core::kGravity);

// The acceleration units an AT2 header states on its first 3 lines ("... IN UNITS OF G",
// "UNITS: CM/S/S", "ACCEL (CM/SEC/SEC)", ...): the name (g, m/s2, cm/s2, in/s2, mm/s2), its m/s^2
// and the header line that said it. Empty when no line names a unit. Reads those lines only.
struct StatedUnits {
  std::string name;
  double to_si = core::kGravity;
  std::string line;
};
std::optional<StatedUnits> at2_stated_units(const std::filesystem::path& path);

// Reads plain text: one column (acceleration; needs dt > 0) or two (time, acceleration; uniform
// spacing is checked). Lines starting with '#' or that are empty are skipped; a non-numeric first
// line is taken as a header. `to_si` converts the file's acceleration units to m/s^2.
core::GroundMotion read_columns(const std::filesystem::path& path, double dt, double to_si);

// Whether the 4th line mentions NPTS (the AT2 header). Throws when the file cannot be opened.
bool is_at2_file(const std::filesystem::path& path);

// Chooses AT2 when the 4th line mentions NPTS (in the units its header states, else g), otherwise
// columns.
core::GroundMotion read_ground_motion(const std::filesystem::path& path, double column_dt = 0.0,
                                      double column_to_si = core::kGravity);

}  // namespace rths::study
