#include "study/delay_trace_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace rths::study {
namespace {

std::filesystem::path temp_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("rths_delay_trace_file_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path;
}

TEST(DelayTrace, ReadsCommentsCommasAndInterpolates) {
  const auto path = temp_file("trace.txt", "# time delay\n0.0, 0.001\n\n1.0 0.003  # note\n");
  const core::DelayTrace trace = read_delay_trace(path);
  ASSERT_EQ(trace.time.size(), 2u);
  EXPECT_DOUBLE_EQ(trace.at(-1.0), 0.001);
  EXPECT_DOUBLE_EQ(trace.at(0.5), 0.002);
  EXPECT_DOUBLE_EQ(trace.at(2.0), 0.003);
  EXPECT_DOUBLE_EQ(trace.max(), 0.003);
  std::filesystem::remove(path);
}

void expect_trace_error(const std::string& text, const std::string& expected_fragment) {
  const auto path = temp_file("bad_trace.txt", text);
  try {
    read_delay_trace(path);
    ADD_FAILURE() << "no error for: " << text;
  } catch (const std::invalid_argument& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find(expected_fragment), std::string::npos) << message;
  }
  std::filesystem::remove(path);
}

TEST(DelayTrace, ErrorsNameFileAndLine) {
  expect_trace_error("0 0.001\n0 0.002\n", ":2: time 0 does not increase");
  expect_trace_error("# c\n0 0.001\n1 abc\n", ":3: 'abc' is not a finite number");
  expect_trace_error("0 0.001 5\n", ":1: expected two columns");
  expect_trace_error("0 -0.001\n", ":1: delay -0.001 is negative");
  expect_trace_error("# nothing\n", "no samples");
  EXPECT_THROW(read_delay_trace("/nonexistent/trace.txt"), std::invalid_argument);
}

}  // namespace
}  // namespace rths::study
