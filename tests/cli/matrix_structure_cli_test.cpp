// `rths run` with structures given by matrices: bad input exits 2 naming file, variable and
// problem; the shipped 20-DOF frame and the RTHS benchmark's case 1 run.
#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/support/run_command_line.h"

namespace {

const std::string kRths = RTHS_EXECUTABLE;
const std::filesystem::path kSource = RTHS_SOURCE_DIR;
const std::string kMotion =
    (std::filesystem::path(RTHS_DATA_DIR) / "ground_motions/RSN175_IMPVALL.H_H-E12140.AT2")
        .string();

rths::test::CommandOutcome run(const std::string& arguments) {
  return rths::test::run_command_line(kRths + " " + arguments);
}

std::filesystem::path scratch() {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_cli_matrix_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

// A study whose structure is `matrices` and whose split is `substructuring`, written to a file.
std::string study(const std::string& name, const std::string& matrices,
                  const std::string& substructuring = "") {
  const auto path = scratch() / (name + ".textproto");
  std::ofstream(path) << "name: \"" << name << "\" structure { matrices { " << matrices
                      << " } damping { modal_zeta: 0.05 } }\n motion { path: \"" << kMotion
                      << "\" duration: 2 }\n integrator { kind: EXPLICIT_NEWMARK dt: 0.002 }\n"
                      << substructuring << "\n cases { name: \"reference\" }\n";
  return path.string() + " --no-plots --out " + (scratch() / name).string();
}

const std::string kMat = (kSource / "configs/benchmark/case_1.mat").string();

void expect_bad_input(const std::string& arguments, const std::vector<std::string>& named) {
  const auto o = run("run " + arguments);
  EXPECT_EQ(o.exit_code, 2) << o.output;
  for (const std::string& text : named)
    EXPECT_NE(o.output.find(text), std::string::npos) << text << "\n" << o.output;
}

TEST(MatrixStructureCli, BadMatricesExitTwoNamingFileVariableAndProblem) {
  expect_bad_input(
      study("not_square", "mass { rows: 1 values: [1, 2] } stiffness { rows: 1 values: 1 }"),
      {"structure.matrices.mass", "1 x 2, not square"});
  expect_bad_input(
      study("not_symmetric",
            "mass { rows: 2 values: [1, 0, 0, 1] } stiffness { rows: 2 values: [2, -1, -1.5, 1] }"),
      {"structure.matrices.stiffness", "not symmetric"});
  expect_bad_input(
      study("not_psd",
            "mass { rows: 2 values: [1, 0, 0, 1] } stiffness { rows: 2 values: [1, 2, 2, 1] }"),
      {"structure.matrices.stiffness", "not positive semi-definite"});
  expect_bad_input(
      study("wrong_size", "mass { rows: 2 values: [1, 0, 0, 1] } stiffness { file: \"" + kMat +
                              "\" variable: \"K\" }"),
      {"structure.matrices.stiffness", "the structure has 2 DOFs"});
  expect_bad_input(study("unknown_variable", "mass { file: \"" + kMat +
                                                 "\" variable: \"M\" } stiffness { file: \"" +
                                                 kMat + "\" variable: \"Kr\" }"),
                   {"structure.matrices.stiffness", "case_1.mat", "no variable 'Kr'"});
  expect_bad_input(study("dof_out_of_range",
                         "mass { file: \"" + kMat + "\" variable: \"M\" } stiffness { file: \"" +
                             kMat + "\" variable: \"K\" }",
                         "substructuring { experimental_dofs { dof: 4 stiffness: 1e6 } }"),
                   {"substructuring.experimental_dofs[0].dof", "4 is outside 1..3"});
}

TEST(MatrixStructureCli, TwentyDofFrameRunsInProcess) {
  const auto out = scratch() / "frame20";
  const auto o = run("run " + (kSource / "configs/matrix_frame20.textproto").string() +
                     " --no-plots --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  std::ifstream csv(out / "results.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_NE(header.find("reference_u_floor20_m"), std::string::npos) << header;
  EXPECT_NE(o.output.find("lag_shift_10ms"), std::string::npos);
}

TEST(MatrixStructureCli, BenchmarkCasePrintsItsCriteriaBesideThePublishedOnes) {
  const auto out = scratch() / "benchmark";
  const auto o = run("run " + (kSource / "configs/benchmark/case_1.textproto").string() +
                     " --no-plots --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("published (sample_controller)"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("vs published"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(out / "benchmark.json"));
}

// --perturbed N: N seeded perturbed-plant draws (case 1 cut to 6 s), J as mean +- std; the same
// seed gives the same figures; a study without a benchmark section is refused.
TEST(MatrixStructureCli, PerturbedPlantsReportMeanAndSpreadOfTheCriteria) {
  const auto dir = scratch() / "perturbed";
  std::filesystem::create_directories(dir);
  for (const char* file : {"case_1.mat", "el_centro.txt"})
    std::filesystem::copy_file(kSource / "configs/benchmark" / file, dir / file,
                               std::filesystem::copy_options::overwrite_existing);
  std::ifstream in(kSource / "configs/benchmark/case_1.textproto");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string scale = "scale: 0.4 }";
  ASSERT_NE(text.find(scale), std::string::npos);
  text.replace(text.find(scale), scale.size(), "scale: 0.4 duration: 6 }");
  std::ofstream(dir / "case_1.textproto") << text;
  const std::string command = "run " + (dir / "case_1.textproto").string() +
                              " --no-plots --perturbed 3 --perturbed-seed 5 --out ";
  const auto first = run(command + (dir / "a").string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("perturbed plants, sample_controller: 3 draws (seed 5), mean +- std"),
            std::string::npos)
      << first.output;
  std::ifstream json_a(dir / "a" / "benchmark_perturbed.json");
  const std::string a((std::istreambuf_iterator<char>(json_a)), std::istreambuf_iterator<char>());
  EXPECT_NE(a.find("\"draws\": 3"), std::string::npos) << a;
  const auto second = run(command + (dir / "b").string());
  ASSERT_EQ(second.exit_code, 0) << second.output;
  std::ifstream json_b(dir / "b" / "benchmark_perturbed.json");
  EXPECT_EQ(
      a, std::string((std::istreambuf_iterator<char>(json_b)), std::istreambuf_iterator<char>()));

  const auto zero = run("run " + (dir / "case_1.textproto").string() +
                        " --no-plots --perturbed 0 --out " + (dir / "c").string());
  EXPECT_EQ(zero.exit_code, 2) << zero.output;
  expect_bad_input(
      study("no_benchmark", "mass { rows: 1 values: 1 } stiffness { rows: 1 values: 100 }") +
          " --perturbed 2",
      {"--perturbed", "no benchmark section"});
}

}  // namespace
