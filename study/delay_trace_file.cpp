#include "study/delay_trace_file.h"

#include <stdexcept>
#include <string>

#include "study/text_columns.h"

namespace rths::study {

core::DelayTrace read_delay_trace(const std::filesystem::path& path) {
  core::DelayTrace trace;
  for (const TextRow& row : read_text_columns(path, "delay trace").rows) {
    const std::string where = text_position(path, row.line);
    if (row.values.size() != 2) {
      throw std::invalid_argument(where + "expected two columns (time, delay), found " +
                                  std::to_string(row.values.size()));
    }
    const double time = row.values[0], delay = row.values[1];
    if (delay < 0.0)
      throw std::invalid_argument(where + "delay " + core::format_number(delay) + " is negative");
    if (!trace.time.empty() && !(time > trace.time.back())) {
      throw std::invalid_argument(where + "time " + core::format_number(time) +
                                  " does not increase (previous " +
                                  core::format_number(trace.time.back()) + ")");
    }
    trace.time.push_back(time);
    trace.delay.push_back(delay);
  }
  if (trace.time.empty())
    throw std::invalid_argument(path.string() + ": delay trace has no samples");
  return trace;
}

}  // namespace rths::study
