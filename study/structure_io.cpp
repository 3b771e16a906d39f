#include "study/structure_io.h"

#include <matio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <vector>

#include "core/number_text.h"
#include "core/sparse_integrators.h"
#include "core/sparse_structure.h"
#include "study/memory_budget.h"
#include "study/motion_files.h"
#include "study/sparse_triplets.h"
#include "study/text_columns.h"

namespace rths::study {
namespace {

[[noreturn]] void fail(const std::string& where, const std::string& problem) {
  throw std::invalid_argument(where + ": " + problem);
}

std::string shape(Eigen::Index rows, Eigen::Index cols) {
  return std::to_string(rows) + " x " + std::to_string(cols);
}

core::Mat inline_matrix(const config::Matrix& spec, const std::string& field) {
  const int count = spec.values_size();
  if (count == 0) fail(field, "no values and no file");
  const int rows = spec.rows() > 0 ? spec.rows() : count;
  if (spec.rows() < 0 || count % rows != 0)
    fail(field,
         std::to_string(count) + " values do not fill " + std::to_string(spec.rows()) + " rows");
  const int cols = count / rows;
  core::Mat m(rows, cols);
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
// column j), real double, held sparse: O(nnz), never rows x cols.
core::SparseMat mat_sparse_matrix(const matvar_t& var, const std::string& named) {
  const auto& sparse = *static_cast<const mat_sparse_t*>(var.data);
  const auto rows = static_cast<Eigen::Index>(var.dims[0]);
  const auto cols = static_cast<Eigen::Index>(var.dims[1]);
  if (var.data_type != MAT_T_DOUBLE || sparse.njc != static_cast<mat_uint32_t>(cols) + 1)
    fail(named, "is a sparse matrix that is not real double");
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(std::min<std::size_t>(sparse.ndata, sparse.nir));
  const auto* values = static_cast<const double*>(sparse.data);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (mat_uint32_t k = sparse.jc[j]; k < sparse.jc[j + 1]; ++k) {
      if (k >= sparse.ndata || k >= sparse.nir || sparse.ir[k] >= static_cast<mat_uint32_t>(rows))
        fail(named, "is a sparse matrix whose indices run past its size");
      triplets.emplace_back(static_cast<Eigen::Index>(sparse.ir[k]), j, values[k]);
    }
  return sparse_from_triplets(rows, cols, std::move(triplets), false);
}

// A full MATLAB variable is sized from its header before its data is read: rows x cols doubles
// (and as much again for the data in its own class while it is converted) against the limit.
void require_mat_size(mat_t* file, const std::string& variable, const std::string& where) {
  std::unique_ptr<matvar_t, MatVarFree> info(Mat_VarReadInfo(file, variable.c_str()));
  if (!info || info->class_type == MAT_C_SPARSE || info->rank != 2) return;
  const std::uint64_t cols = info->dims[1], most = std::numeric_limits<std::uint64_t>::max();
  require_memory(static_cast<std::uint64_t>(info->dims[0]), cols > most / 16 ? most : cols * 16,
                 where + ": variable '" + variable + "' read as a dense matrix");
}

MatrixData mat_matrix(const std::filesystem::path& path, const std::string& variable,
                      const std::string& where) {
  if (variable.empty()) fail(where, "a .mat file needs `variable`, the name of the matrix in it");
  std::unique_ptr<mat_t, MatFileCloser> file(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!file) fail(where, "cannot be opened as a MATLAB file");
  require_mat_size(file.get(), variable, where);
  std::unique_ptr<matvar_t, MatVarFree> var(Mat_VarRead(file.get(), variable.c_str()));
  if (!var)
    fail(where, "no variable '" + variable + "' (variables: " + mat_variables(file.get()) + ")");
  const std::string named = where + ": variable '" + variable + "'";
  if (var->rank != 2) fail(named, "has " + std::to_string(var->rank) + " dimensions, not 2");
  MatrixData out;
  if (var->class_type == MAT_C_SPARSE && !var->isComplex && var->data != nullptr) {
    out.sparse = mat_sparse_matrix(*var, named);
    out.sparse_held = true;
    return out;
  }
  if (var->isComplex || var->data == nullptr)
    fail(named, "is not a real numeric matrix (complex, sparse, a struct, a cell or an object)");
  const auto rows = static_cast<Eigen::Index>(var->dims[0]);
  const auto cols = static_cast<Eigen::Index>(var->dims[1]);
  out.dense.resize(rows, cols);  // column-major, as MATLAB stores it
  if (!to_double(*var, out.dense.data(), out.dense.size()))
    fail(named, "is not a real numeric matrix (complex, sparse, a struct, a cell or an object)");
  return out;
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

// A Matrix Market file's data lines (comments and blank lines skipped), each as its numbers.
class MarketLines {
 public:
  MarketLines(std::istream& in, std::string where) : in_(in), where_(std::move(where)) {}
  bool next() {
    while (std::getline(in_, line_)) {
      ++line_no_;
      const std::size_t first = line_.find_first_not_of(" \t\r");
      if (first == std::string::npos || line_[first] == '%') continue;
      split();
      return true;
    }
    return false;
  }
  const std::vector<double>& numbers() const { return numbers_; }
  std::string at() const { return where_ + ":" + std::to_string(line_no_); }

 private:
  void split() {
    numbers_.clear();
    const std::string_view text(line_);
    std::size_t begin = text.find_first_not_of(" \t\r");
    while (begin != std::string_view::npos) {
      const std::size_t end = std::min(text.find_first_of(" \t\r", begin), text.size());
      const std::string_view token = text.substr(begin, end - begin);
      const auto value = core::parse_finite(token);
      if (!value)
        fail(at(), core::printable(token).insert(0, 1, '\'') + "' is not a finite number");
      numbers_.push_back(*value);
      begin = text.find_first_not_of(" \t\r", end);
    }
  }
  std::istream& in_;
  std::string where_, line_;
  std::vector<double> numbers_;
  int line_no_ = 1;  // the header
};

int market_index(double value, Eigen::Index size, const MarketLines& lines) {
  if (value != std::floor(value) || value < 1 || value > static_cast<double>(size))
    fail(lines.at(),
         "index " + core::format_number(value) + " is outside 1.." + std::to_string(size));
  return static_cast<int>(value) - 1;
}

// The size line against what the file can hold and the memory limit, before anything is
// allocated: an 81-byte file that claims 1e9 entries is refused at once, and so is a size whose
// storage the limit cannot hold: a coordinate file's kSparseBytesPerEntry an entry it declares
// (twice for a symmetric one, both triangles), an array's 8 bytes a cell (it is dense). An entry
// line is at least "1 1 0\n" (coordinate) or "0\n" (array).
void check_market_size(const std::vector<double>& size, const MarketHeader& header,
                       std::uintmax_t file_bytes, const std::string& at) {
  const double rows = size[0], cols = size[1];
  if (header.symmetric && rows != cols) fail(at, "a symmetric matrix must be square");
  const double cells = header.symmetric ? rows * (rows + 1) / 2 : rows * cols;
  const double entries = header.coordinate ? size[2] : cells;
  if (header.coordinate && (entries != std::floor(entries) || entries < 0 || entries > cells))
    fail(at, "declares " + core::format_number(entries) + " entries, more than its " +
                 core::format_number(cells) + " cells (or not a count)");
  const double line_bytes = header.coordinate ? 6.0 : 2.0;
  if (entries * line_bytes > static_cast<double>(file_bytes))
    fail(at, "declares " + core::format_number(entries) + " entries, more than its " +
                 std::to_string(file_bytes) + " bytes can hold (at least " +
                 core::format_number(line_bytes) + " bytes an entry)");
  if (header.coordinate)
    require_memory(static_cast<std::uint64_t>(entries) * (header.symmetric ? 2 : 1) +
                       static_cast<std::uint64_t>(cols),
                   kSparseBytesPerEntry, at + ": the sparse matrix its size line declares");
  else
    require_memory(static_cast<std::uint64_t>(rows), static_cast<std::uint64_t>(cols) * 8,
                   at + ": the dense matrix its size line declares");
}

// Coordinate entries as triplets (both triangles of a symmetric file), into a sparse matrix: a
// repeated entry keeps its last value, as a dense fill would; explicit zeros are dropped.
core::SparseMat market_coordinate(MarketLines& lines, Eigen::Index rows, Eigen::Index cols,
                                  Eigen::Index entries, bool symmetric, const std::string& where) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(symmetric ? 2 * entries : entries));
  Eigen::Index filled = 0;
  while (lines.next()) {
    if (filled >= entries) fail(lines.at(), "more entries than the size line declares");
    const std::vector<double>& v = lines.numbers();
    if (v.size() != 3) fail(lines.at(), "an entry is 'row col value'");
    const int i = market_index(v[0], rows, lines), j = market_index(v[1], cols, lines);
    triplets.emplace_back(i, j, v[2]);
    ++filled;
  }
  if (filled != entries)
    fail(where,
         "declares " + std::to_string(entries) + " entries but holds " + std::to_string(filled));
  return sparse_from_triplets(rows, cols, std::move(triplets), symmetric);
}

// Array entries, column by column (a symmetric file: the lower triangle, column by column).
core::Mat market_array(MarketLines& lines, Eigen::Index rows, Eigen::Index cols, bool symmetric,
                       const std::string& where) {
  core::Mat m = core::Mat::Zero(rows, cols);
  const Eigen::Index entries = symmetric ? rows * (rows + 1) / 2 : m.size();
  Eigen::Index filled = 0;
  while (lines.next()) {
    if (filled >= entries) fail(lines.at(), "more entries than the size line declares");
    if (lines.numbers().size() != 1) fail(lines.at(), "an array entry is one value");
    const double value = lines.numbers()[0];
    Eigen::Index i = filled % rows, j = filled / rows;  // column-major
    if (symmetric) {
      j = 0;
      Eigen::Index k = filled;
      while (k >= rows - j) k -= rows - j++;
      i = j + k;
      m(j, i) = value;
    }
    m(i, j) = value;
    ++filled;
  }
  if (filled != entries)
    fail(where,
         "declares " + std::to_string(entries) + " entries but holds " + std::to_string(filled));
  return m;
}

MatrixData market_matrix(const std::filesystem::path& path, const std::string& where) {
  std::error_code error;
  const std::uintmax_t file_bytes = std::filesystem::file_size(path, error);
  std::ifstream in(path);
  if (!in) fail(where, "cannot be opened");
  std::string line;
  if (!std::getline(in, line)) fail(where, "is empty");
  const MarketHeader header = market_header(line, where);
  MarketLines lines(in, where);
  if (!lines.next()) fail(where, "has no size line");
  const std::vector<double> v = lines.numbers();
  constexpr double kMaxSize = kMaxMatrixDimension;
  if (v.size() != (header.coordinate ? 3u : 2u) || v[0] < 1 || v[1] < 1 || v[0] > kMaxSize ||
      v[1] > kMaxSize || v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]))
    fail(lines.at(), "the size line must be 'rows cols" +
                         std::string(header.coordinate ? " entries'" : "'") + " (each 1.." +
                         std::to_string(kMaxMatrixDimension) + ")");
  check_market_size(v, header, error ? 0 : file_bytes, lines.at());
  const auto rows = static_cast<Eigen::Index>(v[0]), cols = static_cast<Eigen::Index>(v[1]);
  MatrixData out;
  if (header.coordinate)
    out.sparse = market_coordinate(lines, rows, cols, static_cast<Eigen::Index>(v[2]),
                                   header.symmetric, where);
  else
    out.dense = market_array(lines, rows, cols, header.symmetric, where);
  out.sparse_held = header.coordinate;
  return out;
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

core::Mat csv_matrix(const std::filesystem::path& path, const std::string& where) {
  require_csv_matrix_size(path, where);
  const TextColumns columns = read_text_columns(path, "matrix");
  if (columns.rows.empty()) fail(where, "has no rows");
  const std::size_t cols = columns.rows.front().values.size();
  core::Mat m(static_cast<Eigen::Index>(columns.rows.size()), static_cast<Eigen::Index>(cols));
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

MatrixData read_matrix_data(const config::Matrix& spec, const std::filesystem::path& base_dir,
                            const std::string& field) {
  MatrixData out;
  if (spec.has_sparse() && (spec.values_size() > 0 || !spec.file().empty()))
    fail(field, "give one of values, file and sparse");
  if (spec.file().empty()) {
    if (!spec.variable().empty())
      fail(field, "`variable` names a .mat variable but no file is given");
    out.sparse_held = spec.has_sparse();
    if (out.sparse_held) out.sparse = read_sparse_triplets(spec.sparse(), field + ".sparse");
    if (!out.sparse_held) out.dense = inline_matrix(spec, field);
    return out;
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
  if (ext != ".csv") fail(where, "unknown extension '" + ext + "' (.mat, .mtx or .csv)");
  out.dense = csv_matrix(path, where);
  return out;
}

namespace {

// A sparse matrix made dense, its n x n doubles checked against the memory limit first.
core::Mat dense_of(MatrixData&& m, const std::string& where) {
  if (!m.sparse_held) return std::move(m.dense);
  require_memory(static_cast<std::uint64_t>(m.rows()), static_cast<std::uint64_t>(m.cols()) * 8,
                 where + ": held dense");
  return core::Mat(m.sparse);
}

void check_square(Eigen::Index rows, Eigen::Index cols, Eigen::Index n, const std::string& where) {
  if (rows != cols) fail(where, "is " + shape(rows, cols) + ", not square");
  if (rows != n)
    fail(where, "is " + shape(rows, cols) + ", the structure has " + std::to_string(n) + " DOFs");
}

void check_square(const core::Mat& m, Eigen::Index n, const std::string& where) {
  check_square(m.rows(), m.cols(), n, where);
  if (!m.allFinite()) fail(where, "holds a value that is not finite");
}

void check_square(const core::SparseMat& m, Eigen::Index n, const std::string& where) {
  check_square(m.rows(), m.cols(), n, where);
  for (Eigen::Index j = 0; j < m.outerSize(); ++j)
    for (core::SparseMat::InnerIterator it(m, j); it; ++it)
      if (!std::isfinite(it.value())) fail(where, "holds a value that is not finite");
}

[[noreturn]] void fail_symmetric(Eigen::Index i, Eigen::Index j, double upper, double lower,
                                 const std::string& where) {
  std::ostringstream why;
  why << "is not symmetric: (" << i + 1 << ", " << j + 1 << ") = " << upper << " but (" << j + 1
      << ", " << i + 1 << ") = " << lower;
  fail(where, why.str());
}

void check_symmetric(const core::Mat& m, const std::string& where) {
  const double scale = m.cwiseAbs().maxCoeff();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = i + 1; j < m.cols(); ++j)
      if (std::abs(m(i, j) - m(j, i)) > 1e-9 * scale) fail_symmetric(i, j, m(i, j), m(j, i), where);
}

// A - A^T, sparse (O(nnz)), to the same 1e-9 of the largest entry as the dense check; the first
// pair named is the dense check's (the lowest row, then column, of the upper triangle).
void check_symmetric(const core::SparseMat& m, const std::string& where) {
  double scale = 0.0;
  for (Eigen::Index k = 0; k < m.nonZeros(); ++k)
    scale = std::max(scale, std::abs(m.valuePtr()[k]));
  const core::SparseMat difference = m - core::SparseMat(m.transpose());
  Eigen::Index row = -1, col = -1;
  for (Eigen::Index j = 0; j < difference.outerSize(); ++j)
    for (core::SparseMat::InnerIterator it(difference, j); it; ++it)
      if (it.row() < it.col() && std::abs(it.value()) > 1e-9 * scale &&
          (row < 0 || it.row() < row || (it.row() == row && it.col() < col))) {
        row = it.row();
        col = it.col();
      }
  if (row >= 0) fail_symmetric(row, col, m.coeff(row, col), m.coeff(col, row), where);
}

// Smallest eigenvalue against `floor` (relative to the largest |eigenvalue|).
void check_definite(const core::Mat& m, bool strictly, const std::string& where) {
  const Eigen::SelfAdjointEigenSolver<core::Mat> solver(0.5 * (m + m.transpose()),
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
void check_definite(const core::SparseMat& m, bool strictly, const std::string& where) {
  if (const auto why = core::check_sparse_definite(m, strictly)) fail(where, *why);
}

// Shapes, finiteness and symmetry of M, C, K in the form the model holds them: the dense
// matrices when it holds them (as every model up to kDenseSchemeMaxDofs does), else the sparse.
void check_shapes_and_symmetry(const core::StructuralModel& model, Eigen::Index n,
                               const std::string& field) {
  const bool dense = model.mass.rows() == n;
  const std::pair<const core::Mat*, const core::SparseMat*> matrices[] = {
      {&model.mass, &model.sparse_mass},
      {&model.stiffness, &model.sparse_stiffness},
      {&model.damping, &model.sparse_damping}};
  const char* names[] = {".mass", ".stiffness", ".damping"};
  for (int pass = 0; pass < 6; ++pass) {  // every shape first, then every symmetry
    const auto [held_dense, held_sparse] = matrices[pass % 3];
    const std::string where = field + names[pass % 3];
    if (pass < 3)
      dense ? check_square(*held_dense, n, where) : check_square(*held_sparse, n, where);
    else
      dense ? check_symmetric(*held_dense, where) : check_symmetric(*held_sparse, where);
  }
}

}  // namespace

core::Mat read_matrix(const config::Matrix& spec, const std::filesystem::path& base_dir,
                      const std::string& field) {
  return dense_of(read_matrix_data(spec, base_dir, field),
                  spec.file().empty() ? field : field + ": " + spec.file());
}

void check_structural_matrices(const core::StructuralModel& model, const std::string& field) {
  const Eigen::Index n = model.dofs();
  if (n < 1) fail(field + ".mass", "is empty");
  check_shapes_and_symmetry(model, n, field);
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

namespace {

core::SparseMat sparse_of(const MatrixData& m) {
  if (m.sparse_held) return m.sparse;
  core::SparseMat out = m.dense.sparseView();
  out.makeCompressed();
  return out;
}

// M, C, K as the model holds them (core/sparse_structure.h's fill rule on the union of their
// patterns): sparse, with dense copies too up to kDenseSchemeMaxDofs (the dense schemes and the
// dense checks, as before), never dense above it; else dense, each n x n checked against the
// memory limit before it is formed. @pre each is n x n.
core::StructuralModel hold_matrices(MatrixData&& mass, MatrixData&& damping, MatrixData&& stiffness,
                                    core::Vec influence, const std::string& field) {
  const Eigen::Index n = mass.rows();
  core::SparseMat m = sparse_of(mass), c = sparse_of(damping), k = sparse_of(stiffness);
  core::SparseMat pattern =
      core::SparseMat(m.cwiseAbs()) + core::SparseMat(c.cwiseAbs()) + core::SparseMat(k.cwiseAbs());
  pattern.prune(0.0);
  if (core::prefer_sparse(n, pattern.nonZeros())) {
    core::StructuralModel model =
        core::make_sparse_model(std::move(m), std::move(c), std::move(k), std::move(influence));
    if (n > core::kDenseSchemeMaxDofs) return model;
    model.mass = core::Mat(model.sparse_mass);
    model.damping = core::Mat(model.sparse_damping);
    model.stiffness = core::Mat(model.sparse_stiffness);
    return model;
  }
  core::StructuralModel model;
  model.mass = dense_of(std::move(mass), field + ".mass");
  model.damping = dense_of(std::move(damping), field + ".damping");
  model.stiffness = dense_of(std::move(stiffness), field + ".stiffness");
  model.influence = std::move(influence);
  return model;
}

}  // namespace

core::StructuralModel read_matrix_structure(const config::MatrixStructure& spec,
                                            const std::filesystem::path& base_dir,
                                            const std::string& field) {
  if (!spec.has_mass()) fail(field + ".mass", "is missing");
  if (!spec.has_stiffness()) fail(field + ".stiffness", "is missing");
  MatrixData mass = read_matrix_data(spec.mass(), base_dir, field + ".mass");
  const Eigen::Index n = mass.rows();
  check_square(mass.rows(), mass.cols(), n, field + ".mass");
  MatrixData stiffness = read_matrix_data(spec.stiffness(), base_dir, field + ".stiffness");
  check_square(stiffness.rows(), stiffness.cols(), n, field + ".stiffness");
  MatrixData damping;
  if (spec.has_damping()) {
    damping = read_matrix_data(spec.damping(), base_dir, field + ".damping");
    check_square(damping.rows(), damping.cols(), n, field + ".damping");
  } else {
    damping.sparse = core::SparseMat(n, n);
    damping.sparse_held = true;
  }
  core::Vec influence = core::Vec::Ones(n);
  if (spec.has_influence()) {
    const core::Mat iota = read_matrix(spec.influence(), base_dir, field + ".influence");
    if (iota.cols() != 1 && iota.rows() != 1)
      fail(field + ".influence", "is " + shape(iota.rows(), iota.cols()) + ", not a vector");
    influence = iota.reshaped();
  }
  core::StructuralModel model = hold_matrices(std::move(mass), std::move(damping),
                                              std::move(stiffness), std::move(influence), field);
  check_structural_matrices(model, field);
  return model;
}

}  // namespace rths::study
