#include "study/motion_files.h"
#include "core/ground_motion.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

namespace rths::study {
namespace {

const std::filesystem::path kMotions = std::filesystem::path(RTHS_DATA_DIR) / "ground_motions";

// The table in shared/data/README.md: file, NPTS, DT (s), PGA (g), time of the PGA (s).
struct Record {
  const char* file;
  std::size_t npts;
  double dt;
  double pga_g;
  double pga_time;
};

class At2Record : public ::testing::TestWithParam<Record> {};

TEST_P(At2Record, MatchesTheDataReadme) {
  const Record& r = GetParam();
  const core::GroundMotion motion = read_at2(kMotions / r.file);
  EXPECT_EQ(motion.acceleration.size(), r.npts);
  EXPECT_DOUBLE_EQ(motion.dt, r.dt);
  // The README quotes PGA to 4 digits in g; the reader returns m/s^2.
  EXPECT_NEAR(motion.peak_abs(), r.pga_g * core::kGravity, 0.00005 * core::kGravity + 1e-12);
  std::size_t at = 0;
  for (std::size_t i = 0; i < motion.acceleration.size(); ++i) {
    if (std::abs(motion.acceleration[i]) > std::abs(motion.acceleration[at])) at = i;
  }
  // Sample i is at t = i dt, the README's convention too.
  EXPECT_NEAR(static_cast<double>(at) * motion.dt, r.pga_time, 1e-9);
  EXPECT_EQ(motion.name, std::filesystem::path(r.file).stem().string());
  // read_ground_motion recognises AT2 by its 4th line.
  EXPECT_EQ(read_ground_motion(kMotions / r.file).acceleration, motion.acceleration);
}

INSTANTIATE_TEST_SUITE_P(
    SharedData, At2Record,
    ::testing::Values(Record{"RSN175_IMPVALL.H_H-E12140.AT2", 7814, 0.005, 0.1449, 10.84},
                      Record{"elcentro_1940_ns_peknold.AT2", 1559, 0.02, 0.3188, 2.02},
                      Record{"IELC180.AT2", 4000, 0.01, 0.3129, 2.15}));

class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rths_ground_motion_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    const auto path = dir_ / name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  // Expects `action` to throw E with a message containing the path and every fragment.
  template <class E, class Action>
  void expect_error(Action action, const std::filesystem::path& path,
                    std::initializer_list<std::string> fragments) {
    try {
      action();
      ADD_FAILURE() << "no error for " << path;
    } catch (const E& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(path.string()), std::string::npos) << message;
      for (const auto& fragment : fragments) {
        EXPECT_NE(message.find(fragment), std::string::npos) << message << " / " << fragment;
      }
    }
  }
  std::filesystem::path dir_;
};

using At2Reader = TempDir;

TEST_F(At2Reader, TruncatedRecordNamesFileAndMissingCount) {
  std::ifstream source(kMotions / "elcentro_1940_ns_peknold.AT2", std::ios::binary);
  std::stringstream whole;
  whole << source.rdbuf();
  const std::string text = whole.str();
  // Cut after the 100th data line: 4 header lines + 100 lines of 8 values.
  std::size_t pos = 0;
  for (int line = 0; line < 104; ++line) pos = text.find('\n', pos) + 1;
  const auto path = write("cut.AT2", text.substr(0, pos));
  expect_error<std::invalid_argument>([&] { read_at2(path); }, path,
                                      {"found 800 values but NPTS = 1559", "759 missing"});
}

// Found by fuzz_at2_motion (fuzz/regressions/at2_motion/npts_beyond_long): an NPTS of 4e41 was
// converted to long (undefined behaviour) and reserved before any value was read.
TEST_F(At2Reader, RefusesAnNptsBeyondAnyRecordBeforeConvertingIt) {
  const std::filesystem::path found =
      std::filesystem::path(RTHS_SOURCE_DIR) / "fuzz/regressions/at2_motion/npts_beyond_long";
  expect_error<std::invalid_argument>([&] { read_at2(found); }, found, {"NPTS above 100000000"});
  for (const std::string& header :
       {"NPTS= 4.07778e41, DT= .02 SEC", "1e300 0.02 NPTS, DT", "NPTS= 100000001, DT= .02 SEC"}) {
    const auto path = write("huge.AT2", "title\nplace\nunits\n" + header + "\n0.1 0.2\n");
    expect_error<std::invalid_argument>([&] { read_at2(path); }, path,
                                        {":4: NPTS above 100000000"});
  }
}

TEST_F(At2Reader, ReadsTheNewNgaHeaderAndGluedFixedWidthFields) {
  const auto path = write("new.AT2",
                          "PEER NGA STRONG MOTION DATABASE RECORD\r\n"
                          "Somewhere, 2000\r\n"
                          "ACCELERATION TIME SERIES IN UNITS OF G\r\n"
                          "5    0.0100    NPTS, DT\r\n"
                          "  .1000000E-01 -.2000000E-01\r\n"
                          "  -0.12345-10.54321   0.5D-01");
  const core::GroundMotion motion = read_at2(path);
  ASSERT_EQ(motion.acceleration.size(), 5u);
  EXPECT_DOUBLE_EQ(motion.dt, 0.01);
  const double expected[] = {0.01, -0.02, -0.12345, -10.54321, 0.05};
  for (int i = 0; i < 5; ++i)
    EXPECT_DOUBLE_EQ(motion.acceleration[i], expected[i] * core::kGravity);
}

TEST_F(At2Reader, ErrorsNameFileLineAndProblem) {
  const std::string head = "a\nb\nc\n";
  const auto no_npts = write("no_npts.AT2", head + "points and step\n0.1\n");
  expect_error<std::invalid_argument>([&] { read_at2(no_npts); }, no_npts, {":4:", "no NPTS"});
  const auto bad_dt = write("bad_dt.AT2", head + "NPTS= 2, DT= -0.01 SEC\n0.1 0.2\n");
  expect_error<std::invalid_argument>([&] { read_at2(bad_dt); }, bad_dt, {":4:", "DT must be > 0"});
  const auto bad_value = write("bad_value.AT2", head + "NPTS= 3, DT= .01 SEC\n0.1 0.2\n0.3x\n");
  expect_error<std::invalid_argument>([&] { read_at2(bad_value); }, bad_value, {":6:", "'x'"});
  const auto too_many = write("too_many.AT2", head + "NPTS= 2, DT= .01 SEC\n0.1 0.2\n0.3\n");
  expect_error<std::invalid_argument>([&] { read_at2(too_many); }, too_many,
                                      {":6:", "more values than NPTS = 2"});
  const auto short_header = write("short.AT2", "a\nb\n");
  expect_error<std::invalid_argument>([&] { read_at2(short_header); }, short_header, {"header"});
  const auto missing = dir_ / "missing.AT2";
  expect_error<std::invalid_argument>([&] { read_at2(missing); }, missing, {"cannot open"});
}

using ColumnReader = TempDir;

TEST_F(ColumnReader, OneColumnNeedsDtAndConvertsUnits) {
  const auto path = write("one.txt", "# acceleration in g\n0.1\n\n-0.2\n0.3\n");
  const core::GroundMotion motion = read_columns(path, 0.02, core::kGravity);
  ASSERT_EQ(motion.acceleration.size(), 3u);
  EXPECT_DOUBLE_EQ(motion.dt, 0.02);
  EXPECT_DOUBLE_EQ(motion.acceleration[1], -0.2 * core::kGravity);
  expect_error<std::invalid_argument>([&] { read_columns(path, 0.0, core::kGravity); }, path,
                                      {"give its sample step"});
  // Not AT2 (no NPTS on line 4): read_ground_motion takes the columns path.
  EXPECT_EQ(read_ground_motion(path, 0.02, 1.0).acceleration[2], 0.3);
}

TEST_F(ColumnReader, TwoColumnsWithHeaderAndCommas) {
  const auto path = write("two.csv", "time,accel\n0.0,1.0\n0.005,2.0\n0.010,3.0\n0.015,4.0\n");
  const core::GroundMotion motion = read_columns(path, 0.0, 1.0);
  ASSERT_EQ(motion.acceleration.size(), 4u);
  EXPECT_NEAR(motion.dt, 0.005, 1e-15);
  EXPECT_DOUBLE_EQ(motion.acceleration[3], 4.0);
  expect_error<std::invalid_argument>([&] { read_columns(path, 0.01, 1.0); }, path, {"disagrees"});
}

TEST_F(ColumnReader, ErrorsNameFileAndLine) {
  const auto uneven = write("uneven.txt", "0 1\n0.01 2\n0.02 3\n0.04 4\n");
  expect_error<std::invalid_argument>([&] { read_columns(uneven, 0.0, 1.0); }, uneven,
                                      {":4:", "non-uniform time"});
  const auto ragged = write("ragged.txt", "0 1\n0.01 2 5\n");
  expect_error<std::invalid_argument>([&] { read_columns(ragged, 0.0, 1.0); }, ragged,
                                      {":2:", "found 3 columns"});
  const auto text = write("text.txt", "time accel\n0 1\n0.01 abc\n");
  expect_error<std::invalid_argument>([&] { read_columns(text, 0.0, 1.0); }, text,
                                      {":3:", "'abc'"});
  const auto wide = write("wide.txt", "1 2 3\n");
  expect_error<std::invalid_argument>([&] { read_columns(wide, 0.0, 1.0); }, wide,
                                      {":1:", "found 3"});
  const auto empty = write("empty.txt", "# nothing\n");
  expect_error<std::invalid_argument>([&] { read_columns(empty, 0.01, 1.0); }, empty,
                                      {"no acceleration values"});
}

TEST(Resampled, LinearInterpolationAndHeldTail) {
  core::GroundMotion ramp{"ramp", 0.02, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}};
  const core::GroundMotion fine = core::resampled(ramp, 0.005);
  ASSERT_EQ(fine.acceleration.size(), 40u);  // same 0.2 s duration
  for (std::size_t j = 0; j <= 36; ++j) EXPECT_NEAR(fine.acceleration[j], j / 4.0, 1e-12) << j;
  for (std::size_t j = 37; j < 40; ++j) EXPECT_DOUBLE_EQ(fine.acceleration[j], 9.0) << j;
  const core::GroundMotion coarse = core::resampled(ramp, 0.05);  // 0.2 s / 0.05 s = 4 samples
  ASSERT_EQ(coarse.acceleration.size(), 4u);
  EXPECT_NEAR(coarse.acceleration[1], 2.5, 1e-12);
  EXPECT_THROW(core::resampled(ramp, 0.0), std::invalid_argument);
}

TEST(Resampled, ElCentroAtOneMillisecondHas31180Steps) {
  const core::GroundMotion motion = read_at2(kMotions / "elcentro_1940_ns_peknold.AT2");
  const core::GroundMotion fine = core::resampled(motion, 0.001);
  EXPECT_EQ(fine.acceleration.size(), 31180u);
  EXPECT_DOUBLE_EQ(fine.acceleration[20], motion.acceleration[1]);  // grid points coincide
  EXPECT_LE(fine.peak_abs(), motion.peak_abs());  // interpolation cannot overshoot
  EXPECT_DOUBLE_EQ(fine.peak_abs(), motion.peak_abs());
}

TEST(ScaledAndTruncated, Basics) {
  const core::GroundMotion motion = read_at2(kMotions / "elcentro_1940_ns_peknold.AT2");
  EXPECT_DOUBLE_EQ(core::scaled(motion, 2.0).peak_abs(), 2.0 * motion.peak_abs());
  EXPECT_THROW(core::scaled(motion, std::nan("")), std::invalid_argument);
  const core::GroundMotion cut = core::truncated(motion, 10.0);
  EXPECT_EQ(cut.acceleration.size(), 500u);
  EXPECT_DOUBLE_EQ(cut.acceleration[499], motion.acceleration[499]);
  EXPECT_EQ(core::truncated(motion, 0.0).acceleration.size(), motion.acceleration.size());
  EXPECT_EQ(core::truncated(motion, 1e6).acceleration.size(), motion.acceleration.size());
}

// A file's extent before it is parsed (motion_file_extent): the AT2 header's NPTS and DT, as the
// reader then finds them.
TEST(MotionFileExtent, AnAt2FilesExtentIsItsHeadersCountAndStep) {
  for (const char* name : {"elcentro_1940_ns_peknold.AT2", "RSN175_IMPVALL.H_H-E12140.AT2"}) {
    const std::optional<MotionFileExtent> extent = motion_file_extent(kMotions / name, true, 0.0);
    ASSERT_TRUE(extent.has_value()) << name;
    const core::GroundMotion read = read_at2(kMotions / name);
    EXPECT_EQ(extent->samples, read.acceleration.size()) << name;
    EXPECT_DOUBLE_EQ(extent->dt, read.dt) << name;
  }
}

// A column file's extent counts the rows the reader finds, less one for a possible title: a line
// of separators only (",") is no row to either, nor a line whose first field is a comment.
TEST(MotionFileExtent, AColumnFilesExtentCountsTheRowsTheReaderReads) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("rths_extent_" + std::to_string(getpid()) + ".txt");
  {
    std::ofstream out(path);
    out << "0.1\n,\n0.2\n , \t\r\n0.3\n,# note\n0.4\n,,\n";
  }
  const std::optional<MotionFileExtent> extent = motion_file_extent(path, false, 0.01);
  const core::GroundMotion read = read_columns(path, 0.01, 1.0);
  std::filesystem::remove(path);
  ASSERT_TRUE(extent.has_value());
  EXPECT_EQ(read.acceleration.size(), 4u);
  EXPECT_EQ(extent->samples, read.acceleration.size() - 1);
}

}  // namespace
}  // namespace rths::study
