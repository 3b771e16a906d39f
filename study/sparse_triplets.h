#pragma once
// A sparse matrix inline in a config (config::Matrix.sparse, proto/config.proto): 0-based
// (row, col, value) triplets, never formed rows x cols. A run record embeds a matrix that was
// read sparse in this form (study/study_inputs.h): O(nnz) bytes, where the dense form holds
// rows x cols doubles (1.6 GB at 10,000 DOFs for a tridiagonal model).
//
//   read_sparse_triplets(triplets, field) -> SparseMat
//     rows and cols 1..kMaxMatrixDimension (symmetric: square); row, col and value of one
//     length; each index below rows (row) or cols (col); each value finite; symmetric: every
//     entry on or below the diagonal (row >= col), mirrored above it. The entries' storage
//     (kSparseBytesPerEntry each, twice an off-diagonal one of a symmetric matrix) is checked
//     against the memory limit (study/memory_budget.h) before a triplet is allocated. As a
//     Matrix Market coordinate file is read: an entry given twice keeps its last value, explicit
//     zeros are dropped. Throws std::invalid_argument naming the field and entry:
//     "structure.matrices.mass.sparse.row[3]: 12 is outside 0..9 (rows 10)".
//   sparse_from_triplets(rows, cols, triplets, symmetric) -> SparseMat
//     the one assembly of every sparse reader (config triplets, Matrix Market coordinate files,
//     MATLAB sparse variables): symmetric mirrors each off-diagonal entry across the diagonal
//     (in place, after the entry: `triplets` needs room for the mirrors to avoid a reallocation),
//     an entry given twice keeps its last value, explicit zeros are dropped, the result is
//     compressed. @pre every index inside rows x cols.
//   write_sparse_triplets(m) -> config::Matrix::SparseTriplets
//     m's stored nonzeros, column by column; an exactly symmetric square m as its lower triangle
//     with `symmetric` set (half the off-diagonal entries). read_sparse_triplets of the result
//     equals m bit for bit (values, indices and pattern; explicit zeros aside).

#include <cstdint>
#include <string>
#include <vector>

#include "core/structure.h"
#include "rths/proto/config.pb.h"

namespace rths::study {

// Rows or columns a matrix of a config may have (a Matrix Market size line's limit too).
constexpr std::uint32_t kMaxMatrixDimension = 100000;

// Bytes an entry of a sparse matrix holds while it is read, all alive at once: its triplet (16),
// Eigen's transposed temporary in setFromTriplets (12), the result (12), the model's copy (12).
constexpr std::uint64_t kSparseBytesPerEntry = 52;

core::SparseMat read_sparse_triplets(const config::Matrix::SparseTriplets& triplets,
                                     const std::string& field);

core::SparseMat sparse_from_triplets(Eigen::Index rows, Eigen::Index cols,
                                     std::vector<Eigen::Triplet<double>> triplets, bool symmetric);

config::Matrix::SparseTriplets write_sparse_triplets(const core::SparseMat& m);

}  // namespace rths::study
