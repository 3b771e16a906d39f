#pragma once
// What the tests of the `rths` binary share: where it and the data are, running it, a scratch
// folder per test and the JSON its --json output carries.
#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/run_command_line.h"

namespace rths::cli_test {

inline const std::string kRths = RTHS_EXECUTABLE;
inline const std::filesystem::path kSource = RTHS_SOURCE_DIR;
inline const std::filesystem::path kData = RTHS_DATA_DIR;
inline const std::string kMotion =
    (kData / "ground_motions/RSN175_IMPVALL.H_H-E12140.AT2").string();

using Outcome = rths::test::CommandOutcome;

inline Outcome run(const std::string& arguments) {
  return rths::test::run_command_line(kRths + " " + arguments);
}

// An empty folder of this test process.
inline std::filesystem::path scratch(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() /
             ("rths_cli_test_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The JSON document of an output that may carry log lines before it.
inline nlohmann::json json_of(const Outcome& o) {
  const auto start = o.output.find('{');
  return nlohmann::json::parse(o.output.substr(start == std::string::npos ? 0 : start));
}

}  // namespace rths::cli_test
