#include "results/write.h"

#include <hdf5.h>
#include <matio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>

#include "results/h5_handle.h"
#include "util/atomic_file.h"

namespace rths::results {
namespace {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

void write_csv(const Table& table, util::AtomicFile& file) {
  std::ofstream& out = file.stream();
  const auto& columns = table.columns();
  for (std::size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c].name;
  out << "\n";
  char number[32];
  for (std::size_t r = 0; r < table.rows(); ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c) out << ",";
      if (columns[c].is_text) {
        out << csv_field(columns[c].texts[r]);
      } else if (const double x = columns[c].numbers[r]; !std::isnan(x)) {
        std::snprintf(number, sizeof number, "%.17g", x);
        out << number;
      }
    }
    out << "\n";
  }
}

// --- MATLAB ------------------------------------------------------------------------------------
struct MatVarDeleter {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using MatVar = std::unique_ptr<matvar_t, MatVarDeleter>;
struct MatFileDeleter {
  void operator()(mat_t* m) const { Mat_Close(m); }
};

// A 1 x n char array that points into `text` (which must outlive it).
matvar_t* mat_char(const char* name, const std::string& text) {
  std::size_t dims[2] = {1, text.size()};
  return Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UTF8, 2, dims, const_cast<char*>(text.data()),
                       MAT_F_DONT_COPY_DATA);
}

// A 1 x 1 double that points at `value` (which must outlive it).
matvar_t* mat_scalar(const double& value) {
  std::size_t dims[2] = {1, 1};
  return Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, const_cast<double*>(&value),
                       MAT_F_DONT_COPY_DATA);
}

MatVar mat_column(const Column& column) {
  std::size_t dims[2] = {column.size(), 1};
  if (!column.is_text) {
    return MatVar(Mat_VarCreate(column.name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims,
                                const_cast<double*>(column.numbers.data()), MAT_F_DONT_COPY_DATA));
  }
  MatVar cell(Mat_VarCreate(column.name.c_str(), MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0));
  if (!cell) return cell;
  for (std::size_t r = 0; r < column.size(); ++r)
    Mat_VarSetCell(cell.get(), static_cast<int>(r), mat_char(nullptr, column.texts[r]));
  return cell;
}

// A 1 x 1 struct whose fields are the given char values.
MatVar mat_text_struct(const char* name,
                       const std::vector<std::pair<std::string, std::string>>& fields) {
  std::vector<const char*> names;
  for (const auto& f : fields) names.push_back(f.first.c_str());
  std::size_t dims[2] = {1, 1};
  MatVar s(Mat_VarCreateStruct(name, 2, dims, names.data(), static_cast<unsigned>(names.size())));
  if (!s) return s;
  for (const auto& f : fields)
    Mat_VarSetStructFieldByName(s.get(), f.first.c_str(), 0, mat_char(nullptr, f.second));
  return s;
}

// The struct `attributes`: a char field per text attribute, a double per number, by name.
MatVar mat_attributes(const Table& table) {
  std::map<std::string, matvar_t*> fields;
  for (const auto& [key, text] : table.attributes()) fields[key] = mat_char(nullptr, text);
  for (const auto& [key, number] : table.number_attributes()) fields[key] = mat_scalar(number);
  std::vector<const char*> names;
  for (const auto& field : fields) names.push_back(field.first.c_str());
  std::size_t dims[2] = {1, 1};
  MatVar s(Mat_VarCreateStruct("attributes", 2, dims, names.data(),
                               static_cast<unsigned>(names.size())));
  // Each field is owned by the struct once set; freed here when there is no struct to own it.
  for (const auto& [key, value] : fields) {
    if (s) {
      Mat_VarSetStructFieldByName(s.get(), key.c_str(), 0, value);
    } else {
      Mat_VarFree(value);
    }
  }
  return s;
}

void write_mat(const Table& table, const std::filesystem::path& path, const std::string& target) {
  for (const Column& c : table.columns()) {
    if (c.name == "units" || c.name == "attributes") {
      throw std::invalid_argument("MATLAB file " + target + ": a column may not be called '" +
                                  c.name + "' (the name holds the units / attributes struct)");
    }
  }
  std::vector<std::string> keys;
  for (const auto& attribute : table.attributes()) keys.push_back(attribute.first);
  for (const auto& attribute : table.number_attributes()) keys.push_back(attribute.first);
  for (const std::string& key : keys) {
    if (!is_identifier(key))
      throw std::invalid_argument("MATLAB file " + target + ": attribute '" + key +
                                  "' is not a valid field name");
  }
  std::unique_ptr<mat_t, MatFileDeleter> mat(Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5));
  if (!mat) throw std::runtime_error("cannot write MATLAB file " + target);
  const auto put = [&](MatVar var, const std::string& what) {
    if (!var || Mat_VarWrite(mat.get(), var.get(), MAT_COMPRESSION_ZLIB) != 0) {
      throw std::runtime_error("cannot write variable '" + what + "' to MATLAB file " + target);
    }
  };
  for (const Column& c : table.columns()) put(mat_column(c), c.name);
  std::vector<std::pair<std::string, std::string>> units;
  for (const Column& c : table.columns()) units.emplace_back(c.name, c.unit);
  if (!units.empty()) put(mat_text_struct("units", units), "units");
  if (!keys.empty()) put(mat_attributes(table), "attributes");
}

// --- HDF5 --------------------------------------------------------------------------------------
class H5Writer {
 public:
  H5Writer(const std::filesystem::path& path, std::string target)
      : target_(std::move(target)),
        file_(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose),
        string_type_(H5Tcopy(H5T_C_S1), H5Tclose) {
    check(file_.ok() && string_type_.ok(), "cannot create the file");
    check(H5Tset_size(string_type_.get(), H5T_VARIABLE) >= 0 &&
              H5Tset_cset(string_type_.get(), H5T_CSET_UTF8) >= 0,
          "cannot make the string type");
  }

  void column(const Column& c) {
    const hsize_t rows = c.size();
    H5Handle space(H5Screate_simple(1, &rows, nullptr), H5Sclose);
    H5Handle properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    check(space.ok() && properties.ok(), "cannot describe column " + c.name);
    if (rows > 0) {
      const hsize_t chunk = std::min<hsize_t>(rows, 1 << 16);
      check(H5Pset_chunk(properties.get(), 1, &chunk) >= 0 &&
                H5Pset_deflate(properties.get(), 4) >= 0,
            "cannot set compression for column " + c.name);
    }
    const hid_t stored = c.is_text ? string_type_.get() : H5T_IEEE_F64LE;
    H5Handle dataset(H5Dcreate2(file_.get(), c.name.c_str(), stored, space.get(), H5P_DEFAULT,
                                properties.get(), H5P_DEFAULT),
                     H5Dclose);
    check(dataset.ok(), "cannot create dataset " + c.name);
    if (rows > 0) {
      herr_t status;
      if (c.is_text) {
        std::vector<const char*> pointers;
        for (const std::string& t : c.texts) pointers.push_back(t.c_str());
        status = H5Dwrite(dataset.get(), string_type_.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT,
                          pointers.data());
      } else {
        status = H5Dwrite(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                          c.numbers.data());
      }
      check(status >= 0, "cannot write dataset " + c.name);
    }
    attribute(dataset.get(), "units", c.unit);
  }

  void root_attribute(const std::string& key, const std::string& value) {
    attribute(file_.get(), key, value);
  }

  void root_attribute(const std::string& key, double value) {
    H5Handle scalar(H5Screate(H5S_SCALAR), H5Sclose);
    H5Handle attr(H5Acreate2(file_.get(), key.c_str(), H5T_IEEE_F64LE, scalar.get(), H5P_DEFAULT,
                             H5P_DEFAULT),
                  H5Aclose);
    check(attr.ok() && H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &value) >= 0,
          "cannot write attribute " + key);
  }

  void close() { check(H5Fflush(file_.get(), H5F_SCOPE_GLOBAL) >= 0, "cannot flush"); }

 private:
  void attribute(hid_t owner, const std::string& key, const std::string& value) {
    H5Handle scalar(H5Screate(H5S_SCALAR), H5Sclose);
    H5Handle attr(
        H5Acreate2(owner, key.c_str(), string_type_.get(), scalar.get(), H5P_DEFAULT, H5P_DEFAULT),
        H5Aclose);
    const char* text = value.c_str();
    check(attr.ok() && H5Awrite(attr.get(), string_type_.get(), &text) >= 0,
          "cannot write attribute " + key);
  }
  void check(bool ok, const std::string& what) const {
    if (!ok) throw std::runtime_error("HDF5 file " + target_ + ": " + what);
  }

  std::string target_;
  H5Handle file_, string_type_;
};

void write_h5(const Table& table, const std::filesystem::path& path, const std::string& target) {
  // Errors are reported by the exceptions below, not by HDF5's stack dump on stderr.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  H5Writer writer(path, target);
  std::string order;
  for (const Column& c : table.columns()) {
    writer.column(c);
    order += (order.empty() ? "" : ",") + c.name;
  }
  writer.root_attribute("columns", order);
  for (const auto& [key, value] : table.attributes()) writer.root_attribute(key, value);
  for (const auto& [key, value] : table.number_attributes()) writer.root_attribute(key, value);
  writer.close();
}

}  // namespace

Format parse_format(const std::string& text) {
  if (text == "csv") return Format::kCsv;
  if (text == "mat") return Format::kMat;
  if (text == "h5") return Format::kH5;
  throw std::invalid_argument("unknown output format '" + text + "' (expected csv, mat or h5)");
}

std::string extension(Format format) {
  switch (format) {
    case Format::kCsv: return ".csv";
    case Format::kMat: return ".mat";
    case Format::kH5: return ".h5";
  }
  return "";
}

void write_table(const Table& table, const std::filesystem::path& path, Format format) {
  util::AtomicFile file(path);
  switch (format) {
    case Format::kCsv: write_csv(table, file); break;
    case Format::kMat: write_mat(table, file.partial_path(), path.string()); break;
    case Format::kH5: write_h5(table, file.partial_path(), path.string()); break;
  }
  file.commit();
}

void require_spreadsheet_size(std::size_t rows, std::size_t columns, const std::string& what) {
  if (rows + 1 <= kSpreadsheetRows && columns <= kSpreadsheetColumns) return;
  throw std::invalid_argument(
      what + ": a CSV of " + std::to_string(rows) + " rows x " + std::to_string(columns) +
      " columns is past what a spreadsheet opens (" + std::to_string(kSpreadsheetRows - 1) +
      " rows under the header, " + std::to_string(kSpreadsheetColumns) +
      " columns): write it with --format h5 (or mat), or keep less with the study's recorders "
      "(a DOF range's step, a recorder's every)");
}

}  // namespace rths::results
