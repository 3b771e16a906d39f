#include "study/structure_io.h"

#include <matio.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "core/sparse_structure.h"
#include "study/memory_budget.h"
#include "study/motion_files.h"
#include "study/text_columns.h"

namespace rths::core {
namespace {

[[noreturn]] void fail(const std::string& where, const std::string& problem) {
  throw std::invalid_argument(where + ": " + problem);
}

std::string shape(Eigen::Index rows, Eigen::Index cols) {
  return std::to_string(rows) + " x " + std::to_string(cols);
}

Mat inline_matrix(const config::Matrix& spec, const std::string& field) {
  const int count = spec.values_size();
  if (count == 0) fail(field, "no values and no file");
  const int rows = spec.rows() > 0 ? spec.rows() : count;
  if (spec.rows() < 0 || count % rows != 0)
    fail(field,
         std::to_string(count) + " values do not fill " + std::to_string(spec.rows()) + " rows");
  const int cols = count / rows;
  Mat m(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) m(i, j) = spec.values(i * cols + j);
  return m;
}

struct MatFileCloser {
  void operator()(mat_t* file) const { Mat_Close(file); }
};
struct MatVarFree {
  void operator()(matvar_t* var) const { Mat_VarFree(var); }
};

template <typename T>
void copy_as_double(const void* data, double* out, Eigen::Index count) {
  const T* in = static_cast<const T*>(data);
  for (Eigen::Index i = 0; i < count; ++i) out[i] = static_cast<double>(in[i]);
}

// A numeric MATLAB array (double, single or integer, as MATLAB saves e.g. uint16 masses) as
// doubles; false for any other class.
bool to_double(const matvar_t& var, double* out, Eigen::Index count) {
  switch (var.class_type) {
    case MAT_C_DOUBLE: copy_as_double<double>(var.data, out, count); return true;
    case MAT_C_SINGLE: copy_as_double<float>(var.data, out, count); return true;
    case MAT_C_INT8: copy_as_double<std::int8_t>(var.data, out, count); return true;
    case MAT_C_UINT8: copy_as_double<std::uint8_t>(var.data, out, count); return true;
    case MAT_C_INT16: copy_as_double<std::int16_t>(var.data, out, count); return true;
    case MAT_C_UINT16: copy_as_double<std::uint16_t>(var.data, out, count); return true;
    case MAT_C_INT32: copy_as_double<std::int32_t>(var.data, out, count); return true;
    case MAT_C_UINT32: copy_as_double<std::uint32_t>(var.data, out, count); return true;
    case MAT_C_INT64: copy_as_double<std::int64_t>(var.data, out, count); return true;
    case MAT_C_UINT64: copy_as_double<std::uint64_t>(var.data, out, count); return true;
    default: return false;
  }
}

std::string mat_variables(mat_t* file) {
  std::string names;
  Mat_Rewind(file);
  while (matvar_t* info = Mat_VarReadNextInfo(file)) {
    if (!names.empty()) names += ", ";
    names += info->name ? info->name : "?";
    Mat_VarFree(info);
  }
  return names.empty() ? "none" : names;
}

// A MATLAB sparse matrix (compressed columns: jc[j]..jc[j+1] index the rows ir and the values of
// column j), real double.
Mat mat_sparse_matrix(const matvar_t& var, const std::string& named) {
  const auto& sparse = *static_cast<const mat_sparse_t*>(var.data);
  const auto rows = static_cast<Eigen::Index>(var.dims[0]);
  const auto cols = static_cast<Eigen::Index>(var.dims[1]);
  if (var.data_type != MAT_T_DOUBLE || sparse.njc != static_cast<mat_uint32_t>(cols) + 1)
    fail(named, "is a sparse matrix that is not real double");
  Mat m = Mat::Zero(rows, cols);
  const auto* values = static_cast<const double*>(sparse.data);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (mat_uint32_t k = sparse.jc[j]; k < sparse.jc[j + 1]; ++k) {
      if (k >= sparse.ndata || k >= sparse.nir || sparse.ir[k] >= static_cast<mat_uint32_t>(rows))
        fail(named, "is a sparse matrix whose indices run past its size");
      m(sparse.ir[k], j) = values[k];
    }
  return m;
}

Mat mat_matrix(const std::filesystem::path& path, const std::string& variable,
               const std::string& where) {
  if (variable.empty()) fail(where, "a .mat file needs `variable`, the name of the matrix in it");
  std::unique_ptr<mat_t, MatFileCloser> file(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!file) fail(where, "cannot be opened as a MATLAB file");
  std::unique_ptr<matvar_t, MatVarFree> var(Mat_VarRead(file.get(), variable.c_str()));
  if (!var)
    fail(where, "no variable '" + variable + "' (variables: " + mat_variables(file.get()) + ")");
  const std::string named = where + ": variable '" + variable + "'";
  if (var->rank != 2) fail(named, "has " + std::to_string(var->rank) + " dimensions, not 2");
  if (var->class_type == MAT_C_SPARSE && !var->isComplex && var->data != nullptr)
    return mat_sparse_matrix(*var, named);
  if (var->isComplex || var->data == nullptr)
    fail(named, "is not a real numeric matrix (complex, sparse, a struct, a cell or an object)");
  const auto rows = static_cast<Eigen::Index>(var->dims[0]);
  const auto cols = static_cast<Eigen::Index>(var->dims[1]);
  Mat m(rows, cols);  // column-major, as MATLAB stores it
  if (!to_double(*var, m.data(), m.size()))
    fail(named, "is not a real numeric matrix (complex, sparse, a struct, a cell or an object)");
  return m;
}

constexpr std::uintmax_t kMaxCsvMatrixBytes = 32ull << 20;  // 32 MiB

// Matrix Market header: "%%MatrixMarket matrix coordinate|array real|integer general|symmetric".
struct MarketHeader {
  bool coordinate = false;
  bool symmetric = false;
};

MarketHeader market_header(const std::string& line, const std::string& where) {
  std::istringstream in(line);
  std::string banner, object, format, field, symmetry;
  in >> banner >> object >> format >> field >> symmetry;
  for (std::string* s : {&object, &format, &field, &symmetry})
    for (char& c : *s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (banner != "%%MatrixMarket" || object != "matrix")
    fail(where, "line 1 is not a '%%MatrixMarket matrix ...' header");
  if (format != "coordinate" && format != "array")
    fail(where, "format '" + format + "' is not coordinate or array");
  if (field != "real" && field != "integer")
    fail(where, "field '" + field + "' is not real or integer");
  if (symmetry != "general" && symmetry != "symmetric")
    fail(where, "symmetry '" + symmetry + "' is not general or symmetric");
  return {format == "coordinate", symmetry == "symmetric"};
}

std::vector<double> market_numbers(const std::string& line, int line_no, const std::string& where) {
  std::vector<double> out;
  std::istringstream in(line);
  std::string token;
  while (in >> token) {
    const auto value = parse_finite(token);
    if (!value)
      fail(where + ":" + std::to_string(line_no), "'" + token + "' is not a finite number");
    out.push_back(*value);
  }
  return out;
}

int market_index(double value, Eigen::Index size, int line_no, const std::string& where) {
  if (value != std::floor(value) || value < 1 || value > static_cast<double>(size))
    fail(where + ":" + std::to_string(line_no),
         "index " + format_number(value) + " is outside 1.." + std::to_string(size));
  return static_cast<int>(value) - 1;
}

// The size line against what the file can hold and the memory limit, before anything is
// allocated: an 81-byte file that claims 1e9 entries, or a size whose dense matrix the machine
// cannot hold, is refused at once. An entry line is at least "1 1 0\n" (coordinate) or "0\n"
// (array).
void check_market_size(const std::vector<double>& size, const MarketHeader& header,
                       std::uintmax_t file_bytes, const std::string& at) {
  const double rows = size[0], cols = size[1];
  if (header.symmetric && rows != cols) fail(at, "a symmetric matrix must be square");
  const double cells = header.symmetric ? rows * (rows + 1) / 2 : rows * cols;
  const double entries = header.coordinate ? size[2] : cells;
  if (header.coordinate && (entries != std::floor(entries) || entries < 0 || entries > cells))
    fail(at, "declares " + format_number(entries) + " entries, more than its " +
                 format_number(cells) + " cells (or not a count)");
  const double line_bytes = header.coordinate ? 6.0 : 2.0;
  if (entries * line_bytes > static_cast<double>(file_bytes))
    fail(at, "declares " + format_number(entries) + " entries, more than its " +
                 std::to_string(file_bytes) + " bytes can hold (at least " +
                 format_number(line_bytes) + " bytes an entry)");
  require_memory(static_cast<std::uint64_t>(rows), static_cast<std::uint64_t>(cols) * 8,
                 at + ": the dense matrix its size line declares");
}

Mat market_matrix(const std::filesystem::path& path, const std::string& where) {
  std::error_code error;
  const std::uintmax_t file_bytes = std::filesystem::file_size(path, error);
  std::ifstream in(path);
  if (!in) fail(where, "cannot be opened");
  std::string line;
  if (!std::getline(in, line)) fail(where, "is empty");
  const MarketHeader header = market_header(line, where);
  int line_no = 1;
  std::vector<double> size;
  Mat m;
  Eigen::Index filled = 0, entries = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '%' || line.find_first_not_of(" \t\r") == std::string::npos)
      continue;
    const std::vector<double> v = market_numbers(line, line_no, where);
    if (size.empty()) {
      if (v.size() != (header.coordinate ? 3u : 2u) || v[0] < 1 || v[1] < 1 || v[0] > 1e5 ||
          v[1] > 1e5)
        fail(where + ":" + std::to_string(line_no),
             "the size line must be 'rows cols" +
                 std::string(header.coordinate ? " entries'" : "'") + " (each 1..100000)");
      check_market_size(v, header, error ? 0 : file_bytes, where + ":" + std::to_string(line_no));
      size = v;
      m = Mat::Zero(static_cast<Eigen::Index>(v[0]), static_cast<Eigen::Index>(v[1]));
      entries = header.coordinate ? static_cast<Eigen::Index>(v[2])
                                  : (header.symmetric ? m.rows() * (m.rows() + 1) / 2 : m.size());
      continue;
    }
    if (filled >= entries)
      fail(where + ":" + std::to_string(line_no), "more entries than the size line declares");
    if (header.coordinate) {
      if (v.size() != 3) fail(where + ":" + std::to_string(line_no), "an entry is 'row col value'");
      const int i = market_index(v[0], m.rows(), line_no, where),
                j = market_index(v[1], m.cols(), line_no, where);
      m(i, j) = v[2];
      if (header.symmetric) m(j, i) = v[2];
    } else {
      if (v.size() != 1) fail(where + ":" + std::to_string(line_no), "an array entry is one value");
      Eigen::Index i = filled % m.rows(), j = filled / m.rows();  // column-major
      if (header.symmetric) {  // lower triangle, column by column
        j = 0;
        Eigen::Index k = filled;
        while (k >= m.rows() - j) k -= m.rows() - j++;
        i = j + k;
        m(j, i) = v[0];
      }
      m(i, j) = v[0];
    }
    ++filled;
  }
  if (size.empty()) fail(where, "has no size line");
  if (filled != entries)
    fail(where,
         "declares " + std::to_string(entries) + " entries but holds " + std::to_string(filled));
  return m;
}

// A CSV matrix is read whole through the text reader, which holds up to
// kMotionReadBytesPerFileByte bytes per byte of file (study/motion_files.h): sized before a byte
// is read, and refused past kMaxCsvMatrixBytes (a spreadsheet's matrix; a model's is .mtx or .mat,
// read sparse) or past what the memory limit can hold.
void require_csv_matrix_size(const std::filesystem::path& path, const std::string& where) {
  std::error_code error;
  const std::uintmax_t bytes = std::filesystem::file_size(path, error);
  if (error) return;
  if (bytes > kMaxCsvMatrixBytes)
    fail(where, std::to_string(bytes) + " bytes, more than the " +
                    std::to_string(kMaxCsvMatrixBytes) +
                    " a .csv matrix may have: write a model this large as Matrix Market (.mtx) "
                    "or MATLAB (.mat); refused before reading it");
  require_memory(bytes, kMotionReadBytesPerFileByte, where + ": reading it as text");
}

Mat csv_matrix(const std::filesystem::path& path, const std::string& where) {
  require_csv_matrix_size(path, where);
  const TextColumns columns = read_text_columns(path, "matrix");
  if (columns.rows.empty()) fail(where, "has no rows");
  const std::size_t cols = columns.rows.front().values.size();
  Mat m(static_cast<Eigen::Index>(columns.rows.size()), static_cast<Eigen::Index>(cols));
  for (std::size_t i = 0; i < columns.rows.size(); ++i) {
    const TextRow& row = columns.rows[i];
    if (row.values.size() != cols)
      fail(text_position(path, row.line) + where, "row has " + std::to_string(row.values.size()) +
                                                      " values, the first has " +
                                                      std::to_string(cols));
    for (std::size_t j = 0; j < cols; ++j)
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = row.values[j];
  }
  return m;
}

}  // namespace

Mat read_matrix(const config::Matrix& spec, const std::filesystem::path& base_dir,
                const std::string& field) {
  if (spec.file().empty()) {
    if (!spec.variable().empty())
      fail(field, "`variable` names a .mat variable but no file is given");
    return inline_matrix(spec, field);
  }
  if (spec.values_size() > 0) fail(field, "give values or a file, not both");
  const std::filesystem::path path = base_dir / spec.file();
  const std::string where = field + ": " + path.string();
  if (!std::filesystem::is_regular_file(path)) fail(where, "no such file");
  const std::string ext = path.extension().string();
  if (ext != ".mat" && !spec.variable().empty())
    fail(where, "`variable` applies to .mat files only");
  if (ext == ".mat") return mat_matrix(path, spec.variable(), where);
  if (ext == ".mtx") return market_matrix(path, where);
  if (ext == ".csv") return csv_matrix(path, where);
  fail(where, "unknown extension '" + ext + "' (.mat, .mtx or .csv)");
}

namespace {

void check_square(const Mat& m, Eigen::Index n, const std::string& where) {
  if (m.rows() != m.cols()) fail(where, "is " + shape(m.rows(), m.cols()) + ", not square");
  if (m.rows() != n)
    fail(where,
         "is " + shape(m.rows(), m.cols()) + ", the structure has " + std::to_string(n) + " DOFs");
  if (!m.allFinite()) fail(where, "holds a value that is not finite");
}

void check_symmetric(const Mat& m, const std::string& where) {
  const double scale = m.cwiseAbs().maxCoeff();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = i + 1; j < m.cols(); ++j)
      if (std::abs(m(i, j) - m(j, i)) > 1e-9 * scale) {
        std::ostringstream why;
        why << "is not symmetric: (" << i + 1 << ", " << j + 1 << ") = " << m(i, j) << " but ("
            << j + 1 << ", " << i + 1 << ") = " << m(j, i);
        fail(where, why.str());
      }
}

// Smallest eigenvalue against `floor` (relative to the largest |eigenvalue|).
void check_definite(const Mat& m, bool strictly, const std::string& where) {
  const Eigen::SelfAdjointEigenSolver<Mat> solver(0.5 * (m + m.transpose()),
                                                  Eigen::EigenvaluesOnly);
  const double largest = solver.eigenvalues().cwiseAbs().maxCoeff();
  const double smallest = solver.eigenvalues().minCoeff();
  const double floor = 1e-9 * largest;
  if (strictly ? !(smallest > floor) : smallest < -floor) {
    std::ostringstream why;
    why << "is not positive " << (strictly ? "definite" : "semi-definite")
        << ": smallest eigenvalue " << smallest << " (largest " << largest << ")";
    fail(where, why.str());
  }
}

// A model held sparse: by the inertia of a shifted LDL^T (core/sparse_structure.h), not by a
// dense eigenproblem.
void check_definite(const SparseMat& m, bool strictly, const std::string& where) {
  if (const auto why = check_sparse_definite(m, strictly)) fail(where, *why);
}

}  // namespace

void check_structural_matrices(const StructuralModel& model, const std::string& field) {
  const Eigen::Index n = model.mass.rows();
  if (n < 1) fail(field + ".mass", "is empty");
  check_square(model.mass, n, field + ".mass");
  check_square(model.stiffness, n, field + ".stiffness");
  check_square(model.damping, n, field + ".damping");
  check_symmetric(model.mass, field + ".mass");
  check_symmetric(model.stiffness, field + ".stiffness");
  check_symmetric(model.damping, field + ".damping");
  if (model.is_sparse()) {
    check_definite(model.sparse_mass, true, field + ".mass");
    check_definite(model.sparse_stiffness, false, field + ".stiffness");
    if (model.sparse_damping.nonZeros() > 0)
      check_definite(model.sparse_damping, false, field + ".damping");
  } else {
    check_definite(model.mass, true, field + ".mass");
    check_definite(model.stiffness, false, field + ".stiffness");
    if (model.damping.cwiseAbs().maxCoeff() > 0)
      check_definite(model.damping, false, field + ".damping");
  }
  if (model.influence.size() != n)
    fail(field + ".influence", "has " + std::to_string(model.influence.size()) +
                                   " entries, the structure " + std::to_string(n) + " DOFs");
  if (!model.influence.allFinite()) fail(field + ".influence", "holds a value that is not finite");
}

StructuralModel read_matrix_structure(const config::MatrixStructure& spec,
                                      const std::filesystem::path& base_dir,
                                      const std::string& field) {
  if (!spec.has_mass()) fail(field + ".mass", "is missing");
  if (!spec.has_stiffness()) fail(field + ".stiffness", "is missing");
  StructuralModel model;
  model.mass = read_matrix(spec.mass(), base_dir, field + ".mass");
  const Eigen::Index n = model.mass.rows();
  model.stiffness = read_matrix(spec.stiffness(), base_dir, field + ".stiffness");
  model.damping = spec.has_damping() ? read_matrix(spec.damping(), base_dir, field + ".damping")
                                     : Mat::Zero(n, n);
  if (spec.has_influence()) {
    const Mat iota = read_matrix(spec.influence(), base_dir, field + ".influence");
    if (iota.cols() != 1 && iota.rows() != 1)
      fail(field + ".influence", "is " + shape(iota.rows(), iota.cols()) + ", not a vector");
    model.influence = iota.reshaped();
  } else {
    model.influence = Vec::Ones(n);
  }
  hold_sparse_if_sparse(model);
  check_structural_matrices(model, field);
  return model;
}

}  // namespace rths::core
