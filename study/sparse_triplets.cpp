#include "study/sparse_triplets.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/number_text.h"
#include "study/memory_budget.h"

namespace rths::study {
namespace {

// Throws "<where>: <the parts, streamed>"; streamed, not concatenated, for GCC 12's -Wrestrict
// false positive on chains of std::string +.
template <typename... Parts>
[[noreturn]] void fail(const std::string& where, const Parts&... parts) {
  std::ostringstream problem;
  problem << where << ": ";
  (problem << ... << parts);
  throw std::invalid_argument(problem.str());
}

std::string entry(const std::string& field, const char* name, int k) {
  std::ostringstream out;
  out << field << '.' << name << '[' << k << ']';
  return out.str();
}

// Sizes, lengths and storage, before anything is allocated.
void check_sizes(const config::Matrix::SparseTriplets& t, const std::string& field) {
  for (const auto& [name, size] : {std::pair{".rows", t.rows()}, std::pair{".cols", t.cols()}})
    if (size < 1 || size > kMaxMatrixDimension)
      fail(field + name, size, " is outside 1..", kMaxMatrixDimension);
  if (t.symmetric() && t.rows() != t.cols())
    fail(field + ".symmetric", "a symmetric matrix must be square, this one is ", t.rows(), " x ",
         t.cols());
  if (t.col_size() != t.row_size() || t.value_size() != t.row_size())
    fail(field, "row, col and value must be of one length, they hold ", t.row_size(), ", ",
         t.col_size(), " and ", t.value_size(), " entries");
  require_memory(static_cast<std::uint64_t>(t.row_size()) * (t.symmetric() ? 2 : 1) + t.cols(),
                 kSparseBytesPerEntry, field + ": the sparse matrix its entries declare");
}

void check_entry(const config::Matrix::SparseTriplets& t, int k, const std::string& field) {
  const std::uint32_t i = t.row(k), j = t.col(k);
  if (i >= t.rows())
    fail(entry(field, "row", k), i, " is outside 0..", t.rows() - 1, " (rows ", t.rows(), ")");
  if (j >= t.cols())
    fail(entry(field, "col", k), j, " is outside 0..", t.cols() - 1, " (cols ", t.cols(), ")");
  if (t.symmetric() && i < j)
    fail(entry(field, "row", k), "(", i, ", ", j,
         ") is above the diagonal of a symmetric matrix, which gives its lower triangle only");
  if (!std::isfinite(t.value(k)))
    fail(entry(field, "value", k), core::format_number(t.value(k)), " is not finite");
}

// Whether m equals its transpose exactly (pattern and values): only then may its upper
// triangle be left to the mirror without changing a bit. @pre m compressed.
bool exactly_symmetric(const core::SparseMat& m) {
  if (m.rows() != m.cols()) return false;
  const core::SparseMat transposed = m.transpose();
  const Eigen::Index n = m.nonZeros();
  return transposed.nonZeros() == n &&
         std::equal(m.outerIndexPtr(), m.outerIndexPtr() + m.outerSize() + 1,
                    transposed.outerIndexPtr()) &&
         std::equal(m.innerIndexPtr(), m.innerIndexPtr() + n, transposed.innerIndexPtr()) &&
         std::equal(m.valuePtr(), m.valuePtr() + n, transposed.valuePtr());
}

}  // namespace

core::SparseMat read_sparse_triplets(const config::Matrix::SparseTriplets& triplets,
                                     const std::string& field) {
  check_sizes(triplets, field);
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(triplets.row_size()) * (triplets.symmetric() ? 2 : 1));
  for (int k = 0; k < triplets.row_size(); ++k) {
    check_entry(triplets, k, field);
    const auto i = static_cast<Eigen::Index>(triplets.row(k));
    const auto j = static_cast<Eigen::Index>(triplets.col(k));
    entries.emplace_back(i, j, triplets.value(k));
  }
  return sparse_from_triplets(static_cast<Eigen::Index>(triplets.rows()),
                              static_cast<Eigen::Index>(triplets.cols()), std::move(entries),
                              triplets.symmetric());
}

core::SparseMat sparse_from_triplets(Eigen::Index rows, Eigen::Index cols,
                                     std::vector<Eigen::Triplet<double>> triplets, bool symmetric) {
  if (symmetric) {  // from the back, so that each mirror lands right after its entry
    const std::size_t given = triplets.size();
    std::size_t write = given + static_cast<std::size_t>(std::count_if(
                                    triplets.begin(), triplets.end(),
                                    [](const auto& t) { return t.row() != t.col(); }));
    triplets.resize(write);
    for (std::size_t read = given; read-- > 0;) {
      const Eigen::Triplet<double> entry = triplets[read];
      if (entry.row() != entry.col())
        triplets[--write] = Eigen::Triplet<double>(entry.col(), entry.row(), entry.value());
      triplets[--write] = entry;
    }
  }
  core::SparseMat m(rows, cols);
  m.setFromTriplets(triplets.begin(), triplets.end(), [](double, double last) { return last; });
  m.prune(0.0);
  m.makeCompressed();
  return m;
}

config::Matrix::SparseTriplets write_sparse_triplets(const core::SparseMat& m) {
  core::SparseMat compressed = m;
  compressed.prune(0.0);
  compressed.makeCompressed();
  const bool symmetric = exactly_symmetric(compressed);
  config::Matrix::SparseTriplets out;
  out.set_rows(static_cast<std::uint32_t>(m.rows()));
  out.set_cols(static_cast<std::uint32_t>(m.cols()));
  out.set_symmetric(symmetric);
  for (Eigen::Index j = 0; j < compressed.outerSize(); ++j)
    for (core::SparseMat::InnerIterator it(compressed, j); it; ++it) {
      if (symmetric && it.row() < it.col()) continue;
      out.add_row(static_cast<std::uint32_t>(it.row()));
      out.add_col(static_cast<std::uint32_t>(it.col()));
      out.add_value(it.value());
    }
  return out;
}

}  // namespace rths::study
