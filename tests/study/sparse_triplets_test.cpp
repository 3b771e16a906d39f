#include "study/sparse_triplets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "study/structure_io.h"

namespace rths::study {
namespace {

using Triplets = config::Matrix::SparseTriplets;

// A chain's stiffness (storeys of k N/m): tridiagonal, symmetric, n x n.
core::SparseMat chain_stiffness(int n, double k) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < n; ++i) {
    entries.emplace_back(i, i, i + 1 < n ? 2 * k : k);
    if (i + 1 < n) {
      entries.emplace_back(i, i + 1, -k);
      entries.emplace_back(i + 1, i, -k);
    }
  }
  core::SparseMat m(n, n);
  m.setFromTriplets(entries.begin(), entries.end());
  m.makeCompressed();
  return m;
}

// Equal pattern and values (== on nonzero doubles: the same bits).
void expect_same(const core::SparseMat& read, const core::SparseMat& written) {
  EXPECT_EQ(read.nonZeros(), written.nonZeros());
  EXPECT_EQ(core::Mat(read), core::Mat(written));
}

Triplets triplets(std::uint32_t rows, std::uint32_t cols,
                  const std::vector<std::tuple<std::uint32_t, std::uint32_t, double>>& entries) {
  Triplets t;
  t.set_rows(rows);
  t.set_cols(cols);
  for (const auto& [i, j, v] : entries) {
    t.add_row(i);
    t.add_col(j);
    t.add_value(v);
  }
  return t;
}

std::string refusal(const Triplets& t) {
  try {
    (void)read_sparse_triplets(t, "structure.matrices.mass.sparse");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

std::string refusal(const config::Matrix& spec) {
  try {
    (void)read_matrix_data(spec, {}, "m");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

TEST(SparseTriplets, ASymmetricChainRoundTripsBitForBitAsItsLowerTriangle) {
  // Storey stiffness not a power of two, so that a value altered in any bit would differ.
  const core::SparseMat k = chain_stiffness(250, 4.0e10 / 3.0);
  const Triplets written = write_sparse_triplets(k);
  EXPECT_TRUE(written.symmetric());
  EXPECT_EQ(written.value_size(), 2 * 250 - 1);  // diagonal + subdiagonal
  expect_same(read_sparse_triplets(written, "k"), k);
}

TEST(SparseTriplets, ANearlySymmetricMatrixIsWrittenWholeSoNoBitChanges) {
  core::SparseMat k = chain_stiffness(6, 1.0);
  k.coeffRef(1, 0) = std::nextafter(-1.0, 0.0);  // within the 1e-9 symmetry check, not exact
  const Triplets written = write_sparse_triplets(k);
  EXPECT_FALSE(written.symmetric());
  EXPECT_EQ(written.value_size(), static_cast<int>(k.nonZeros()));
  expect_same(read_sparse_triplets(written, "k"), k);
}

TEST(SparseTriplets, ARepeatedEntryKeepsItsLastValueAndZerosAreDropped) {
  const core::SparseMat m =
      read_sparse_triplets(triplets(2, 3, {{0, 2, 1.0}, {0, 2, 5.0}, {1, 0, 0.0}}), "m");
  EXPECT_EQ(m.nonZeros(), 1);
  EXPECT_EQ(m.coeff(0, 2), 5.0);
}

TEST(SparseTriplets, MalformedTripletsAreRefusedNamingTheField) {
  const std::string field = "structure.matrices.mass.sparse";
  EXPECT_EQ(refusal(triplets(3, 3, {{3, 0, 1.0}})), field + ".row[0]: 3 is outside 0..2 (rows 3)");
  EXPECT_EQ(refusal(triplets(3, 3, {{0, 0, 1.0}, {1, 7, 1.0}})),
            field + ".col[1]: 7 is outside 0..2 (cols 3)");
  EXPECT_EQ(refusal(triplets(0, 3, {})), field + ".rows: 0 is outside 1..100000");
  EXPECT_EQ(refusal(triplets(3, 200000, {})), field + ".cols: 200000 is outside 1..100000");
  Triplets uneven = triplets(3, 3, {{0, 0, 1.0}});
  uneven.add_row(1);
  EXPECT_EQ(refusal(uneven), field +
                                 ": row, col and value must be of one length, they hold 2, 1 and "
                                 "1 entries");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(refusal(triplets(3, 3, {{0, 0, 1.0}, {2, 1, nan}})),
            field + ".value[1]: nan is not finite");
  Triplets upper = triplets(3, 3, {{0, 0, 1.0}, {0, 1, 2.0}});
  upper.set_symmetric(true);
  EXPECT_NE(refusal(upper).find(field + ".row[1]: (0, 1) is above the diagonal"), std::string::npos)
      << refusal(upper);
  Triplets oblong = triplets(2, 3, {});
  oblong.set_symmetric(true);
  EXPECT_EQ(refusal(oblong), field +
                                 ".symmetric: a symmetric matrix must be square, this one "
                                 "is 2 x 3");
}

TEST(SparseTriplets, EntriesBeyondTheMemoryLimitAreRefusedBeforeTheyAreRead) {
  Triplets t = triplets(1000, 1000, {});
  for (std::uint32_t i = 0; i < 1000; ++i) {
    t.add_row(i);
    t.add_col(i);
    t.add_value(1.0);
  }
  setenv("RTHS_MEMORY_LIMIT", "10000", 1);
  const std::string why = refusal(t);
  unsetenv("RTHS_MEMORY_LIMIT");
  EXPECT_NE(why.find("structure.matrices.mass.sparse: the sparse matrix its entries declare"),
            std::string::npos)
      << why;
}

TEST(SparseTriplets, AConfigMatrixGivesSparseOrValuesOrAFileNotTwo) {
  config::Matrix spec;
  *spec.mutable_sparse() = triplets(1, 1, {{0, 0, 2.0}});
  const MatrixData read = read_matrix_data(spec, {}, "structure.matrices.mass");
  ASSERT_TRUE(read.sparse_held);
  EXPECT_EQ(read.sparse.coeff(0, 0), 2.0);
  EXPECT_EQ(read_matrix(spec, {}, "m")(0, 0), 2.0);
  spec.add_values(2.0);
  EXPECT_EQ(refusal(spec), "m: give one of values, file and sparse");
  spec.clear_values();
  spec.set_file("mass.mtx");
  EXPECT_EQ(refusal(spec), "m: give one of values, file and sparse");
}

}  // namespace
}  // namespace rths::study
