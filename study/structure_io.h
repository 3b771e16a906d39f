#pragma once
// Matrices of a structure given by its matrices, read from a study's config: inline values or a
// file, and the checks every structural matrix must pass.
//
//   read_matrix(spec, base_dir, field) -> Mat
//     inline:  `values` row-major with `rows` rows (a vector: one column of `values.size()`),
//              or `sparse` triplets (study/sparse_triplets.h), held sparse;
//     `.mat`:  the MATLAB variable `variable` (v5, v7.3), real, 2-D, full or sparse (double);
//     `.mtx`:  Matrix Market, `matrix coordinate|array real|integer general|symmetric`;
//     `.csv`:  one matrix row per line, fields separated by commas or blanks ('#' comments).
//   Relative paths resolve against base_dir. A Matrix Market coordinate file and a MATLAB sparse
//   variable are read as triplets into a sparse matrix, never rows x cols: a coordinate file's
//   declared entries, at 52 bytes each (triplet, Eigen's temporary, compressed entry, the held
//   copy), are checked against the memory limit (study/memory_budget.h) before an entry is read
//   (a sparse MATLAB variable is read by matio as stored, its file bounded by the file-size
//   limit, and not sized before); read_matrix then forms the dense
//   matrix only after checking its rows x cols x 8 bytes against the limit too. Every error throws std::invalid_argument naming the
//   field, the file and (for .mat) the variable, and the problem: "structure.matrices.mass:
//   frame.mat: no variable 'Mx' (variables: M, C, K)".
//
//   check_structural_matrices: M symmetric positive definite, K symmetric positive semi-definite
//   and C symmetric positive semi-definite, each n x n; iota of length n. Symmetry is judged to a
//   relative 1e-9 of the largest entry (on a model held sparse only: A - A' sparse, O(nnz));
//   definiteness by the eigenvalues (tolerance 1e-9 of the largest), or on a model held sparse by
//   the pivots of a shifted sparse LDL^T (core::check_sparse_definite, tolerance 1e-9 ||A||_inf),
//   so condensed models rounded on export still pass.
//
//   read_matrix_structure holds the model as core/sparse_structure.h's fill rule says, judged on
//   the matrices as read: sparse (with dense copies too up to kDenseSchemeMaxDofs, for the dense
//   schemes and checks), else dense; above kDenseSchemeMaxDofs a sparse model is never formed
//   dense, from the first entry read to the last step.

#include <filesystem>
#include <string>

#include "core/structure.h"
#include "rths/proto/config.pb.h"

namespace rths::study {

// A matrix as its source holds it: sparse (Matrix Market coordinate, a MATLAB sparse variable,
// inline `sparse` triplets), read into triplets and never formed rows x cols, or dense (inline
// values, .csv, Matrix Market array, a full MATLAB variable).
struct MatrixData {
  core::Mat dense;
  core::SparseMat sparse;
  bool sparse_held = false;
  Eigen::Index rows() const { return sparse_held ? sparse.rows() : dense.rows(); }
  Eigen::Index cols() const { return sparse_held ? sparse.cols() : dense.cols(); }
};

// The matrix of `spec` as its source holds it, read and sized as read_matrix says; not formed
// dense.
MatrixData read_matrix_data(const config::Matrix& spec, const std::filesystem::path& base_dir,
                            const std::string& field);

core::Mat read_matrix(const config::Matrix& spec, const std::filesystem::path& base_dir,
                      const std::string& field);

// The structure of structure.matrices: M, K, damping (matrix, or from Structure.damping by the
// caller when absent: returned zero), iota; checked. `field` prefixes every error.
core::StructuralModel read_matrix_structure(const config::MatrixStructure& spec,
                                            const std::filesystem::path& base_dir,
                                            const std::string& field);

// Throws std::invalid_argument "<field>.<name>: <problem>" when a matrix is not square, not n x n,
// not symmetric, or not definite as required (see above); `where` names the matrices' source.
void check_structural_matrices(const core::StructuralModel& model, const std::string& field);

}  // namespace rths::study
