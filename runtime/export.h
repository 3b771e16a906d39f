#pragma once
// Run record -> CSV, one row per step:
//   step, time, ground_acceleration, u<i>, v<i>, a<i> (per DOF), command<j>, realised<j>, force<j>
//   (per actuator), then per link (node id n): node<n>_answered_step, node<n>_injected_lag,
//   node<n>_round_trip, node<n>_one_way_down, node<n>_one_way_up, then lateness, overrun.
// Units SI (s, m, m/s, m/s^2, N). Doubles are printed with 17 significant digits (round-trip exact).

#include <filesystem>

#include "runtime/record.h"

namespace rths::runtime {

// Throws std::invalid_argument when the record has no header, std::runtime_error when the file
// cannot be written. Returns the number of rows written.
std::size_t write_csv(const RecordContents& record, const std::filesystem::path& csv);

}  // namespace rths::runtime
