#pragma once
// Delay-trace files: a measured or designed delay over time for a TraceShift stage
// (core/delay.h). Two whitespace- or comma-separated columns, time (s, increasing) and delay
// (s, >= 0); '#' comments. Errors throw std::invalid_argument naming the file and line.

#include <filesystem>

#include "core/delay.h"

namespace rths::study {

core::DelayTrace read_delay_trace(const std::filesystem::path& path);

}  // namespace rths::study
