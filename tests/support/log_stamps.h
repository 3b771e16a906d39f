#pragma once
// What the trial harnesses (fault_trial, controller_trial) read back from a run's logs: a whole
// file, and the CLOCK_REALTIME stamp (ns) a process's log line carries ("realtime_ns N").

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <string>

namespace rths::test {

// The file's text; "" when it cannot be read (a process that never wrote its log).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// realtime_ns of the first log line that holds `marker` and a "realtime_ns N" stamp.
inline std::optional<std::int64_t> stamped_line(const std::string& log, const std::string& marker) {
  static const std::regex stamp("realtime_ns ([0-9]+)");
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (line.find(marker) != std::string::npos && std::regex_search(line, m, stamp))
      return std::stoll(m[1]);
  }
  return std::nullopt;
}

}  // namespace rths::test
