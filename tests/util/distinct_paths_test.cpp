#include "util/distinct_paths.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <fstream>
#include <stdexcept>
#include <string>

namespace rths::util {
namespace {

std::filesystem::path scratch() {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_distinct_paths_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(DistinctPaths, RefusesTheInputAsOutputNamingBoth) {
  const auto dir = scratch();
  const auto record = dir / "R.rthsrec";
  std::ofstream(record) << "x";
  try {
    refuse_output_over_input({"--csv", record}, {{"record", record}});
    FAIL() << "an output over its input was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--csv"), std::string::npos) << message;
    EXPECT_NE(message.find("input record"), std::string::npos) << message;
  }
  std::filesystem::remove_all(dir);
}

TEST(DistinctPaths, SeesThroughSpellingsAndLinks) {
  const auto dir = scratch();
  const auto file = dir / "a.csv";
  std::ofstream(file) << "x";
  std::filesystem::create_symlink(file, dir / "link.csv");
  EXPECT_TRUE(same_file(file, dir / "." / "a.csv"));
  EXPECT_TRUE(same_file(file, dir / "link.csv"));
  EXPECT_TRUE(same_file(dir / "sub" / ".." / "new.csv", dir / "new.csv"));  // neither exists
  EXPECT_FALSE(same_file(file, dir / "b.csv"));
  EXPECT_NO_THROW(refuse_output_over_input({"--csv", dir / "b.csv"}, {{"record", file}}));
  EXPECT_NO_THROW(refuse_output_over_input({"--csv", ""}, {{"record", file}}));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::util
