// results::write_table: the CSV text exactly, MATLAB / HDF5 file signatures and errors. The
// contents of .mat and .h5 files are read back by independent readers (scipy, h5py) in
// readback_test.py.
#include "results/write.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <limits>
#include <sstream>

namespace rths::results {
namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_tables_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Table sample() {
  Table t;
  t.add_numbers("time_s", "s", {0.0, 0.1, 1e-20});
  t.add_numbers("u1_m", "m", {1.0 / 3.0, std::numeric_limits<double>::quiet_NaN(), -2});
  t.add_texts("label", "", {"a", "b,c", "say \"hi\""});
  t.set_attribute("case_name", "lag_shift_14ms");
  return t;
}

TEST(WriteTest, CsvHasNamesExactNumbersEmptyNanAndQuotedText) {
  const auto dir = scratch("csv");
  write_table(sample(), dir / "t.csv", Format::kCsv);
  EXPECT_EQ(read(dir / "t.csv"),
            "time_s,u1_m,label\n"
            "0,0.33333333333333331,a\n"
            "0.10000000000000001,,\"b,c\"\n"
            "9.9999999999999995e-21,-2,\"say \"\"hi\"\"\"\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "t.csv.partial"));
}

TEST(WriteTest, MatAndH5FilesCarryTheirFormatsSignature) {
  const auto dir = scratch("binary");
  write_table(sample(), dir / "t.mat", Format::kMat);
  write_table(sample(), dir / "t.h5", Format::kH5);
  EXPECT_EQ(read(dir / "t.mat").rfind("MATLAB 5.0 MAT-file", 0), 0u);
  EXPECT_EQ(read(dir / "t.h5").substr(0, 8), std::string("\x89HDF\r\n\x1a\n", 8));
  EXPECT_FALSE(std::filesystem::exists(dir / "t.mat.partial"));
  EXPECT_FALSE(std::filesystem::exists(dir / "t.h5.partial"));
}

TEST(WriteTest, ErrorsNameTheProblemAndLeaveNoFile) {
  const auto dir = scratch("errors");
  Table clash;
  clash.add_numbers("units", "", {1});
  try {
    write_table(clash, dir / "c.mat", Format::kMat);
    FAIL() << "a column called 'units' was written to MATLAB";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'units'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "c.mat"));
  EXPECT_FALSE(std::filesystem::exists(dir / "c.mat.partial"));
  std::filesystem::create_directories(dir / "ro");
  std::filesystem::permissions(
      dir / "ro", std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
  if (::geteuid() != 0) {  // root writes anywhere
    EXPECT_THROW(write_table(sample(), dir / "ro" / "t.h5", Format::kH5), std::runtime_error);
  }
  EXPECT_THROW(write_table(sample(), "/proc/rths_no/t.h5", Format::kH5), std::runtime_error);
  EXPECT_THROW(write_table(sample(), "/proc/rths_no/t.mat", Format::kMat), std::runtime_error);
  EXPECT_THROW(parse_format("xlsx"), std::invalid_argument);
  EXPECT_EQ(parse_format("h5"), Format::kH5);
  EXPECT_EQ(extension(Format::kMat), ".mat");
}

}  // namespace
}  // namespace rths::results
