#pragma once
// Ground-motion files: readers for PEER AT2 (both dialects seen in the wild) and plain column
// text, into core::GroundMotion (time in s, acceleration in m/s^2; AT2 values, in g, are
// multiplied by kGravity).

#include <filesystem>

#include "core/ground_motion.h"

namespace rths::core {

// Reads a PEER AT2 file: 4 header lines, the 4th holding NPTS and DT in either of the forms
// "NPTS=  1559, DT=   .0200 SEC" or "7814    0.0050    NPTS, DT", then values in g in any
// whitespace-separated layout (8F10.5, 5E15.7, ...). Throws std::invalid_argument (bad input)
// naming the file and line when the header is malformed, a value does not parse, or fewer than NPTS
// values are found.
GroundMotion read_at2(const std::filesystem::path& path);

// Reads plain text: one column (acceleration; needs dt > 0) or two (time, acceleration; uniform
// spacing is checked). Lines starting with '#' or that are empty are skipped; a non-numeric first
// line is taken as a header. `to_si` converts the file's acceleration units to m/s^2.
GroundMotion read_columns(const std::filesystem::path& path, double dt, double to_si);

// Whether the 4th line mentions NPTS (the AT2 header). Throws when the file cannot be opened.
bool is_at2_file(const std::filesystem::path& path);

// Chooses AT2 when the 4th line mentions NPTS, otherwise columns.
GroundMotion read_ground_motion(const std::filesystem::path& path, double column_dt = 0.0,
                                double column_to_si = kGravity);

}  // namespace rths::core
