#include "study/structure_io.h"

#include <gtest/gtest.h>

#include <matio.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <vector>

namespace rths::study {
namespace {

namespace fs = std::filesystem;

fs::path scratch() {
  const fs::path dir =
      fs::temp_directory_path() / ("rths_structure_io_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

fs::path write(const std::string& name, const std::string& text) {
  const fs::path path = scratch() / name;
  std::ofstream(path) << text;
  return path;
}

config::Matrix file_spec(const std::string& name, const std::string& variable = "") {
  config::Matrix spec;
  spec.set_file(name);
  spec.set_variable(variable);
  return spec;
}

config::Matrix inline_spec(int rows, std::vector<double> values) {
  config::Matrix spec;
  spec.set_rows(rows);
  for (double v : values) spec.add_values(v);
  return spec;
}

// The message of the std::invalid_argument `f` throws ("" if none).
template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

fs::path benchmark_dir() { return fs::path(RTHS_SOURCE_DIR) / "configs" / "benchmark"; }

TEST(StructureIo, InlineValuesAreRowMajor) {
  const core::Mat m = read_matrix(inline_spec(2, {1, 2, 3, 4}), {}, "f");
  EXPECT_EQ(m(0, 1), 2.0);
  EXPECT_EQ(m(1, 0), 3.0);
  const core::Mat column = read_matrix(inline_spec(0, {1, 1, 1}), {}, "f");
  EXPECT_EQ(column.rows(), 3);
  EXPECT_NE(error_of([] {
              read_matrix(inline_spec(2, {1, 2, 3}), {}, "mass");
            }).find("mass: 3 values"),
            std::string::npos);
}

TEST(StructureIo, MatrixMarketCoordinateSymmetricFillsBothTriangles) {
  write("sym.mtx",
        "%%MatrixMarket matrix coordinate real symmetric\n% comment\n3 3 4\n1 1 2\n2 1 -1\n2 2 "
        "2\n3 3 1.5\n");
  const core::Mat m = read_matrix(file_spec("sym.mtx"), scratch(), "f");
  EXPECT_EQ(m(0, 1), -1.0);
  EXPECT_EQ(m(1, 0), -1.0);
  EXPECT_EQ(m(2, 2), 1.5);
  EXPECT_EQ(m(0, 2), 0.0);
}

TEST(StructureIo, MatrixMarketArrayIsColumnMajorAndSymmetricIsTheLowerTriangle) {
  write("general.mtx", "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n");
  const core::Mat g = read_matrix(file_spec("general.mtx"), scratch(), "f");
  EXPECT_EQ(g(1, 0), 2.0);
  EXPECT_EQ(g(0, 1), 3.0);
  write("lower.mtx", "%%MatrixMarket matrix array real symmetric\n3 3\n1\n2\n3\n4\n5\n6\n");
  const core::Mat s = read_matrix(file_spec("lower.mtx"), scratch(), "f");
  core::Mat expected(3, 3);
  expected << 1, 2, 3, 2, 4, 5, 3, 5, 6;
  EXPECT_EQ(s, expected);
}

TEST(StructureIo, MatrixMarketErrorsNameTheFileAndLine) {
  write("bad_index.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1.0\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("bad_index.mtx"), scratch(), "structure.matrices.mass");
            }).find("bad_index.mtx:3: index 3 is outside 1..2"),
            std::string::npos);
  write("short.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("short.mtx"), scratch(), "f");
            }).find("declares 2 entries but holds 1"),
            std::string::npos);
  write("complex.mtx", "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("complex.mtx"), scratch(), "f");
            }).find("field 'complex'"),
            std::string::npos);
}

TEST(StructureIo, AMatrixMarketSizeLineIsCheckedBeforeAnythingIsAllocated) {
  // 81 bytes that claim 1e9 entries, a symmetric matrix that is not square, more entries than
  // cells, and a dense matrix beyond the memory limit: each refused at the size line.
  write("liar.mtx",
        "%%MatrixMarket matrix coordinate real general\n30000 30000 1000000000\n1 1 1\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("liar.mtx"), scratch(), "f");
            }).find("liar.mtx:2: declares 1e+09 entries, more than its"),
            std::string::npos)
      << error_of([] { read_matrix(file_spec("liar.mtx"), scratch(), "f"); });
  write("oblong.mtx", "%%MatrixMarket matrix coordinate real symmetric\n2 3 1\n1 1 1\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("oblong.mtx"), scratch(), "f");
            }).find("a symmetric matrix must be square"),
            std::string::npos);
  write("crowded.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 2\n1 1 1\n1 1 2\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("crowded.mtx"), scratch(), "f");
            }).find("declares 2 entries, more than its 1 cells"),
            std::string::npos);
  // 1 MB: a 1000 x 1000 dense matrix is 8 MB. Its one entry is read sparse; made dense (the
  // dense reader) it is refused before it is formed.
  setenv("RTHS_MEMORY_LIMIT", "1000000", 1);
  write("big.mtx", "%%MatrixMarket matrix coordinate real general\n1000 1000 1\n1 1 1\n");
  const std::string big = error_of([] { read_matrix(file_spec("big.mtx"), scratch(), "f"); });
  // 100 bytes: the 4 entries a size line declares, held sparse (52 bytes each with the column
  // starts), do not fit: refused at the size line.
  setenv("RTHS_MEMORY_LIMIT", "100", 1);
  write("four.mtx",
        "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 1\n1 2 1\n2 1 1\n2 2 1\n");
  const std::string four = error_of([] { read_matrix(file_spec("four.mtx"), scratch(), "f"); });
  unsetenv("RTHS_MEMORY_LIMIT");
  EXPECT_NE(big.find("f: big.mtx: held dense keeps 1000 rows x 8000 bytes"), std::string::npos)
      << big;
  EXPECT_NE(four.find("four.mtx:2: the sparse matrix its size line declares keeps 6 rows x 52"),
            std::string::npos)
      << four;
}

TEST(StructureIo, ACsvMatrixIsSizedBeforeItIsRead) {
  // 33 MiB of zeros: past the 32 MiB a .csv matrix may have, refused before a byte is parsed.
  {
    std::ofstream big(scratch() / "huge.csv");
    const std::string row(1 << 20, '0');
    for (int i = 0; i < 33; ++i) big << row << "\n";
  }
  const std::string error = error_of([] { read_matrix(file_spec("huge.csv"), scratch(), "f"); });
  EXPECT_NE(error.find("a .csv matrix may have: write a model this large as Matrix Market"),
            std::string::npos)
      << error;
  fs::remove(scratch() / "huge.csv");
  // Within the size, a memory limit that cannot hold its reading: refused naming the limit.
  write("small.csv", "1,2\n3,4\n");
  setenv("RTHS_MEMORY_LIMIT", "100", 1);
  const std::string tight = error_of([] { read_matrix(file_spec("small.csv"), scratch(), "f"); });
  unsetenv("RTHS_MEMORY_LIMIT");
  EXPECT_NE(tight.find("small.csv: reading it as text"), std::string::npos) << tight;
  EXPECT_EQ(error_of([] { read_matrix(file_spec("small.csv"), scratch(), "f"); }), "");
}

TEST(StructureIo, CsvRowsAndRaggedRowsRefused) {
  write("k.csv", "# stiffness\n2,-1\n-1,2\n");
  EXPECT_EQ(read_matrix(file_spec("k.csv"), scratch(), "f")(1, 0), -1.0);
  write("ragged.csv", "2,-1\n-1\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("ragged.csv"), scratch(), "f");
            }).find("row has 1 values"),
            std::string::npos);
}

TEST(StructureIo, MatFileVariablesIncludingMatlabsUint16Mass) {
  // The RTHS benchmark's case 1 (configs/benchmark/README.md): M saved by MATLAB as uint16.
  const core::Mat m = read_matrix(file_spec("case_1.mat", "M"), benchmark_dir(), "f");
  EXPECT_EQ(m, 1000.0 * core::Mat::Identity(3, 3));
  const core::Mat k = read_matrix(file_spec("case_1.mat", "K"), benchmark_dir(), "f");
  EXPECT_NEAR(k(0, 0), 26054883.87960384, 1e-6);
  EXPECT_NEAR(k(1, 2), -14419970.77723698, 1e-6);
  const std::string unknown = error_of([] {
    read_matrix(file_spec("case_1.mat", "Kx"), benchmark_dir(), "structure.matrices.stiffness");
  });
  EXPECT_NE(unknown.find("structure.matrices.stiffness: "), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("case_1.mat: no variable 'Kx' (variables: "), std::string::npos)
      << unknown;
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("case_1.mat"), benchmark_dir(), "f");
            }).find("needs `variable`"),
            std::string::npos);
}

// A full MATLAB variable is sized from its header (rows x cols, 16 bytes a cell while it is
// converted) before its data is read: case 1's 3 x 3 K needs 144 bytes, refused under 100.
TEST(StructureIo, AFullMatVariableIsSizedFromItsHeaderBeforeItIsRead) {
  setenv("RTHS_MEMORY_LIMIT", "100", 1);
  const std::string error =
      error_of([] { read_matrix(file_spec("case_1.mat", "K"), benchmark_dir(), "f"); });
  unsetenv("RTHS_MEMORY_LIMIT");
  EXPECT_NE(error.find("case_1.mat: variable 'K' read as a dense matrix keeps 3 rows x 48 bytes"),
            std::string::npos)
      << error;
}

// A MATLAB sparse matrix (as `save` writes sparse(K)): compressed columns, read in full.
TEST(StructureIo, MatFileSparseVariable) {
  // K = [2 -1 0; -1 2 -1; 0 -1 1] by columns: rows ir, column starts jc, values.
  mat_uint32_t ir[] = {0, 1, 0, 1, 2, 1, 2};
  mat_uint32_t jc[] = {0, 2, 5, 7};
  double values[] = {2, -1, -1, 2, -1, -1, 1};
  mat_sparse_t sparse{};
  sparse.nzmax = 7;
  sparse.ir = ir;
  sparse.nir = 7;
  sparse.jc = jc;
  sparse.njc = 4;
  sparse.ndata = 7;
  sparse.data = values;
  const fs::path path = scratch() / "sparse.mat";
  mat_t* file = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  ASSERT_NE(file, nullptr);
  size_t dims[] = {3, 3};
  matvar_t* var =
      Mat_VarCreate("K", MAT_C_SPARSE, MAT_T_DOUBLE, 2, dims, &sparse, MAT_F_DONT_COPY_DATA);
  ASSERT_NE(var, nullptr);
  ASSERT_EQ(Mat_VarWrite(file, var, MAT_COMPRESSION_NONE), 0);
  Mat_VarFree(var);
  Mat_Close(file);
  core::Mat expected(3, 3);
  expected << 2, -1, 0, -1, 2, -1, 0, -1, 1;
  EXPECT_EQ(read_matrix(file_spec("sparse.mat", "K"), scratch(), "f"), expected);
}

TEST(StructureIo, MissingFileAndUnknownExtension) {
  EXPECT_NE(
      error_of([] { read_matrix(file_spec("none.mtx"), scratch(), "f"); }).find("no such file"),
      std::string::npos);
  write("m.txt", "1\n");
  EXPECT_NE(error_of([] {
              read_matrix(file_spec("m.txt"), scratch(), "f");
            }).find("unknown extension '.txt'"),
            std::string::npos);
}

core::StructuralModel two_dof() {
  core::StructuralModel model;
  model.mass = core::Mat::Identity(2, 2);
  model.stiffness = (core::Mat(2, 2) << 2, -1, -1, 1).finished();
  model.damping = core::Mat::Zero(2, 2);
  model.influence = core::Vec::Ones(2);
  return model;
}

TEST(StructureIo, ChecksNameTheMatrixAndTheProblem) {
  EXPECT_EQ(error_of([] { check_structural_matrices(two_dof(), "s"); }), "");
  core::StructuralModel m = two_dof();
  m.stiffness(0, 1) = -1.5;
  EXPECT_NE(error_of([&] {
              check_structural_matrices(m, "s");
            }).find("s.stiffness: is not symmetric: (1, 2) = -1.5"),
            std::string::npos);
  m = two_dof();
  m.stiffness(0, 0) = -2;
  EXPECT_NE(error_of([&] {
              check_structural_matrices(m, "s");
            }).find("s.stiffness: is not positive semi-definite"),
            std::string::npos);
  m = two_dof();
  m.mass(1, 1) = 0;
  EXPECT_NE(
      error_of([&] { check_structural_matrices(m, "s"); }).find("s.mass: is not positive definite"),
      std::string::npos);
  m = two_dof();
  m.damping = core::Mat::Zero(2, 3);
  EXPECT_NE(
      error_of([&] { check_structural_matrices(m, "s"); }).find("s.damping: is 2 x 3, not square"),
      std::string::npos);
  m = two_dof();
  m.damping = core::Mat::Zero(3, 3);
  EXPECT_NE(error_of([&] { check_structural_matrices(m, "s"); }).find("the structure has 2 DOFs"),
            std::string::npos);
  m = two_dof();
  m.influence = core::Vec::Ones(3);
  EXPECT_NE(error_of([&] { check_structural_matrices(m, "s"); }).find("s.influence: has 3 entries"),
            std::string::npos);
}

TEST(StructureIo, MatrixStructureFromFilesWithDefaultInfluence) {
  config::MatrixStructure spec;
  *spec.mutable_mass() = file_spec("frame20_mass.mtx");
  *spec.mutable_stiffness() = file_spec("frame20_stiffness.mtx");
  const core::StructuralModel model = read_matrix_structure(
      spec, fs::path(RTHS_SOURCE_DIR) / "configs" / "matrices", "structure.matrices");
  EXPECT_EQ(model.dofs(), 20);
  EXPECT_EQ(model.influence, core::Vec::Ones(20));
  EXPECT_EQ(model.mass(0, 1), 100.0);  // the mass matrix is not diagonal
  EXPECT_EQ(model.damping, core::Mat::Zero(20, 20));
}

namespace sparse_models {

// A chain of n floors as Matrix Market (lower triangle): M = m I, K tridiagonal of storeys k.
void write_chain(const std::string& prefix, int n, double m, double k) {
  std::ofstream mass(scratch() / (prefix + "_mass.mtx"));
  mass << "%%MatrixMarket matrix coordinate real symmetric\n" << n << " " << n << " " << n << "\n";
  for (int i = 1; i <= n; ++i) mass << i << " " << i << " " << m << "\n";
  std::ofstream stiffness(scratch() / (prefix + "_stiffness.mtx"));
  stiffness << "%%MatrixMarket matrix coordinate real symmetric\n"
            << n << " " << n << " " << 2 * n - 1 << "\n";
  for (int i = 1; i <= n; ++i) {
    stiffness << i << " " << i << " " << (i < n ? 2 * k : k) << "\n";
    if (i > 1) stiffness << i << " " << i - 1 << " " << -k << "\n";
  }
}

config::MatrixStructure chain_spec(const std::string& prefix) {
  config::MatrixStructure spec;
  *spec.mutable_mass() = file_spec(prefix + "_mass.mtx");
  *spec.mutable_stiffness() = file_spec(prefix + "_stiffness.mtx");
  return spec;
}

// A 3000-DOF chain under a 20 MB memory limit: one of its matrices held dense would be 72 MB,
// so reading it dense anywhere (file, checks, damping) would be refused; held sparse it is
// about 0.2 MB.
TEST(StructureIo, ALargeSparseModelIsHeldSparseFromTheFileOn) {
  write_chain("chain3000", 3000, 1e5, 4e10);
  setenv("RTHS_MEMORY_LIMIT", "20000000", 1);
  core::StructuralModel model;
  const std::string error = error_of([&] {
    model = read_matrix_structure(chain_spec("chain3000"), scratch(), "structure.matrices");
  });
  unsetenv("RTHS_MEMORY_LIMIT");
  ASSERT_EQ(error, "");
  EXPECT_EQ(model.dofs(), 3000);
  ASSERT_TRUE(model.is_sparse());
  EXPECT_EQ(model.mass.size(), 0);  // no dense copy above kDenseSchemeMaxDofs
  EXPECT_EQ(model.stiffness.size(), 0);
  EXPECT_EQ(model.sparse_stiffness.nonZeros(), 3 * 3000 - 2);  // both triangles
  EXPECT_EQ(model.sparse_stiffness.coeff(1, 0), -4e10);
  EXPECT_EQ(model.sparse_stiffness.coeff(0, 1), -4e10);
  EXPECT_EQ(model.sparse_stiffness.coeff(2999, 2999), 4e10);
  EXPECT_EQ(model.sparse_damping.nonZeros(), 0);
  EXPECT_EQ(model.influence, core::Vec::Ones(3000));
}

// Up to kDenseSchemeMaxDofs a sparse model also holds its dense copies (the dense schemes and
// checks), equal to the sparse form.
TEST(StructureIo, ASmallSparseModelKeepsDenseCopiesEqualToItsSparseForm) {
  write_chain("chain150", 150, 2.0, 300.0);
  const core::StructuralModel model =
      read_matrix_structure(chain_spec("chain150"), scratch(), "structure.matrices");
  ASSERT_TRUE(model.is_sparse());
  EXPECT_EQ(model.stiffness, core::Mat(model.sparse_stiffness));
  EXPECT_EQ(model.mass, core::Mat(model.sparse_mass));
  EXPECT_EQ(model.stiffness(149, 148), -300.0);
  EXPECT_EQ(model.damping, core::Mat::Zero(150, 150));
}

// The checks on the sparse form name the matrix, the pair and the problem as the dense ones do.
TEST(StructureIo, ASparseModelIsCheckedOnItsSparseForm) {
  write_chain("asym", 2500, 1e5, 4e10);
  {  // K(3, 2) = -4e10 but K(2, 3) = -3e10: not symmetric (a general file, both given)
    std::ofstream k(scratch() / "asym_stiffness.mtx");
    k << "%%MatrixMarket matrix coordinate real general\n2500 2500 " << 3 * 2500 - 2 << "\n";
    for (int i = 1; i <= 2500; ++i) {
      k << i << " " << i << " " << (i < 2500 ? 8e10 : 4e10) << "\n";
      if (i > 1) k << i << " " << i - 1 << " " << -4e10 << "\n";
      if (i > 1) k << i - 1 << " " << i << " " << (i == 3 ? -3e10 : -4e10) << "\n";
    }
  }
  EXPECT_NE(error_of([] {
              read_matrix_structure(chain_spec("asym"), scratch(), "s");
            }).find("s.stiffness: is not symmetric: (2, 3) = -3e+10 but (3, 2) = -4e+10"),
            std::string::npos)
      << error_of([] { read_matrix_structure(chain_spec("asym"), scratch(), "s"); });
  // 15000 DOFs whose M holds one entry (the 79-byte file): refused as not definite, on
  // the sparse form, within a 100 MB limit (dense it would be 1.8 GB).
  write("one_mass.mtx", "%%MatrixMarket matrix coordinate real general\n15000 15000 1\n1 1 1\n");
  write_chain("wide", 15000, 1e5, 4e10);
  config::MatrixStructure spec = chain_spec("wide");
  *spec.mutable_mass() = file_spec("one_mass.mtx");
  setenv("RTHS_MEMORY_LIMIT", "100000000", 1);
  const std::string error = error_of([&] { read_matrix_structure(spec, scratch(), "s"); });
  unsetenv("RTHS_MEMORY_LIMIT");
  EXPECT_NE(error.find("s.mass: is not positive definite"), std::string::npos) << error;
}

// A MATLAB sparse variable (as `save` writes sparse(K)) is held sparse too: a 2500-DOF chain's
// K given as compressed columns.
TEST(StructureIo, AMatFileSparseVariableIsHeldSparse) {
  const int n = 2500;
  std::vector<mat_uint32_t> ir, jc{0};
  std::vector<double> values;
  for (int j = 0; j < n; ++j) {
    for (int i = std::max(0, j - 1); i <= std::min(n - 1, j + 1); ++i) {
      ir.push_back(static_cast<mat_uint32_t>(i));
      values.push_back(i == j ? (j < n - 1 ? 2.0 : 1.0) : -1.0);
    }
    jc.push_back(static_cast<mat_uint32_t>(ir.size()));
  }
  mat_sparse_t sparse{};
  sparse.nzmax = sparse.nir = sparse.ndata = static_cast<mat_uint32_t>(ir.size());
  sparse.ir = ir.data();
  sparse.jc = jc.data();
  sparse.njc = static_cast<mat_uint32_t>(jc.size());
  sparse.data = values.data();
  const fs::path path = scratch() / "chain_k.mat";
  mat_t* file = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  ASSERT_NE(file, nullptr);
  size_t dims[] = {static_cast<size_t>(n), static_cast<size_t>(n)};
  matvar_t* var =
      Mat_VarCreate("K", MAT_C_SPARSE, MAT_T_DOUBLE, 2, dims, &sparse, MAT_F_DONT_COPY_DATA);
  ASSERT_NE(var, nullptr);
  ASSERT_EQ(Mat_VarWrite(file, var, MAT_COMPRESSION_NONE), 0);
  Mat_VarFree(var);
  Mat_Close(file);
  write_chain("matk", n, 1.0, 1.0);
  config::MatrixStructure spec = chain_spec("matk");
  *spec.mutable_stiffness() = file_spec("chain_k.mat", "K");
  const core::StructuralModel model = read_matrix_structure(spec, scratch(), "s");
  ASSERT_TRUE(model.is_sparse());
  EXPECT_EQ(model.stiffness.size(), 0);
  EXPECT_EQ(model.sparse_stiffness.nonZeros(), 3 * n - 2);
  EXPECT_EQ(model.sparse_stiffness.coeff(n - 1, n - 2), -1.0);
  EXPECT_EQ(model.sparse_stiffness.coeff(n - 1, n - 1), 1.0);
}

}  // namespace sparse_models
}  // namespace
}  // namespace rths::study
