// results::write_table: the CSV text exactly, MATLAB / HDF5 file signatures, the attributes and
// units as libmatio and libhdf5 read them back, and errors. The contents of .mat and .h5 files
// are also read back by independent readers (scipy, h5py) in readback_test.py.
#include "results/write.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <matio.h>
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
  t.add_numbers("u_floor1_m", "m", {1.0 / 3.0, std::numeric_limits<double>::quiet_NaN(), -2});
  t.add_texts("label", "", {"a", "b,c", "say \"hi\""});
  t.set_attribute("case_name", "lag_shift_14ms");
  t.set_number_attribute("dt_s", 0.001);
  return t;
}

// Field `field` of the struct variable `variable` in a MATLAB file: its class and, for char, its
// text, for double, its first value.
struct MatField {
  matio_classes kind = MAT_C_EMPTY;
  std::string text;
  double number = 0.0;
};
MatField mat_field(const std::filesystem::path& path, const char* variable, const char* field) {
  MatField out;
  mat_t* file = Mat_Open(path.c_str(), MAT_ACC_RDONLY);
  if (!file) return out;
  matvar_t* s = Mat_VarRead(file, variable);
  matvar_t* f = s ? Mat_VarGetStructFieldByName(s, field, 0) : nullptr;
  if (f) {
    out.kind = f->class_type;
    // Characters come back 1 byte (UTF-8) or 2 bytes (UTF-16) wide; the tests' text is ASCII.
    if (f->class_type == MAT_C_CHAR && f->data) {
      const auto* bytes = static_cast<const unsigned char*>(f->data);
      for (std::size_t i = 0; f->data_size > 0 && i < f->nbytes; i += f->data_size)
        out.text += static_cast<char>(bytes[i]);
    }
    if (f->class_type == MAT_C_DOUBLE && f->data) out.number = *static_cast<const double*>(f->data);
  }
  Mat_VarFree(s);
  Mat_Close(file);
  return out;
}

// Attribute `key` of `object` ("/" or a dataset) in an HDF5 file: its type class and its text
// (a variable-length string) or number (a float64).
struct H5Attribute {
  H5T_class_t kind = H5T_NO_CLASS;
  std::string text;
  double number = 0.0;
};
H5Attribute h5_attribute(const std::filesystem::path& path, const char* object, const char* key) {
  H5Attribute out;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t attr = H5Aopen_by_name(file, object, key, H5P_DEFAULT, H5P_DEFAULT);
  const hid_t type = H5Aget_type(attr);
  out.kind = H5Tget_class(type);
  if (out.kind == H5T_STRING) {
    char* text = nullptr;
    if (H5Aread(attr, type, &text) >= 0 && text) out.text = text;
    H5free_memory(text);
  } else if (out.kind == H5T_FLOAT) {
    H5Aread(attr, H5T_NATIVE_DOUBLE, &out.number);
  }
  H5Tclose(type);
  H5Aclose(attr);
  H5Fclose(file);
  return out;
}

TEST(WriteTest, CsvHasNamesExactNumbersEmptyNanAndQuotedText) {
  const auto dir = scratch("csv");
  write_table(sample(), dir / "t.csv", Format::kCsv);
  EXPECT_EQ(read(dir / "t.csv"),
            "time_s,u_floor1_m,label\n"
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

TEST(WriteTest, MatHoldsTextAttributesAsCharNumbersAsDoublesAndEachColumnsUnit) {
  const auto dir = scratch("mat_attributes");
  write_table(sample(), dir / "t.mat", Format::kMat);
  const MatField case_name = mat_field(dir / "t.mat", "attributes", "case_name");
  EXPECT_EQ(case_name.kind, MAT_C_CHAR);
  EXPECT_EQ(case_name.text, "lag_shift_14ms");
  const MatField dt = mat_field(dir / "t.mat", "attributes", "dt_s");
  EXPECT_EQ(dt.kind, MAT_C_DOUBLE);
  EXPECT_EQ(dt.number, 0.001);
  EXPECT_EQ(mat_field(dir / "t.mat", "units", "u_floor1_m").text, "m");
  EXPECT_EQ(mat_field(dir / "t.mat", "units", "time_s").text, "s");
}

TEST(WriteTest, H5HoldsTextAttributesAsStringsNumbersAsFloatsAndEachColumnsUnit) {
  const auto dir = scratch("h5_attributes");
  write_table(sample(), dir / "t.h5", Format::kH5);
  const H5Attribute case_name = h5_attribute(dir / "t.h5", "/", "case_name");
  EXPECT_EQ(case_name.kind, H5T_STRING);
  EXPECT_EQ(case_name.text, "lag_shift_14ms");
  const H5Attribute dt = h5_attribute(dir / "t.h5", "/", "dt_s");
  EXPECT_EQ(dt.kind, H5T_FLOAT);
  EXPECT_EQ(dt.number, 0.001);
  EXPECT_EQ(h5_attribute(dir / "t.h5", "u_floor1_m", "units").text, "m");
  EXPECT_EQ(h5_attribute(dir / "t.h5", "/", "columns").text, "time_s,u_floor1_m,label");
}

// A CSV is for a spreadsheet: one past its 1,048,576 rows (the header one) or 16,384 columns is
// refused naming both sizes and the formats that hold it.
TEST(WriteTest, ACsvPastWhatASpreadsheetOpensIsRefusedNamingTheFix) {
  EXPECT_NO_THROW(require_spreadsheet_size(kSpreadsheetRows - 1, kSpreadsheetColumns, "t.csv"));
  try {
    require_spreadsheet_size(kSpreadsheetRows, 10, "results.csv");
    ADD_FAILURE() << "1,048,576 rows under a header accepted";
  } catch (const std::invalid_argument& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("results.csv: a CSV of 1048576 rows x 10 columns"), std::string::npos)
        << why;
    EXPECT_NE(why.find("--format h5"), std::string::npos) << why;
  }
  EXPECT_THROW(require_spreadsheet_size(10, kSpreadsheetColumns + 1, "t.csv"),
               std::invalid_argument);
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
