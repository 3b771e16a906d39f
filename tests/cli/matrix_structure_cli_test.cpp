// `rths run` with structures given by matrices: bad input exits 2 naming file, variable and
// problem; the shipped 20-DOF frame and the RTHS benchmark's case 1 run.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <nlohmann/json.hpp>

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
  EXPECT_NE(o.output.find("against the published values"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("J1 diff (ms)"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("J4 (%)   100 std(x_m - d_ref) / std(d_ref)"), std::string::npos)
      << o.output;
  std::ifstream in(out / "benchmark.json");
  const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"name\": \"J9\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"definition\""), std::string::npos) << json;
  EXPECT_EQ(json.find("J2-J9 %"), std::string::npos) << json;
}

// `rths stability --study` on a compensated loop of several DOFs gives the verdict `rths run` gives
// before the run, by the modal approximation, stated as such (it used to refuse any non-SDOF).
TEST(MatrixStructureCli, StabilityOfACompensatedLoopOnSeveralDofsIsModal) {
  const auto path = scratch() / "frame3_poly.textproto";
  std::ofstream(path)
      << "name: \"frame3\" structure { matrices { "
         "mass { rows: 3 values: [1000, 0, 0, 0, 1000, 0, 0, 0, 800] } "
         "stiffness { rows: 3 values: [4e6, -2e6, 0, -2e6, 3.5e6, -1.5e6, 0, -1.5e6, 1.5e6] } "
         "damping { rows: 3 values: [2275.816349, -809.9103853, 0, -809.9103853, 2073.338753, "
         "-607.432789, 0, -607.432789, 1132.229252] } } }\n"
      << "motion { path: \"" << kMotion << "\" }\n"
      << "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_dofs { dof: 1 stiffness: 0.5e6 } }\n"
         "cases { name: \"reference\" } cases { name: \"poly\" delay { shift { delay: 0.010 } } "
         "compensation { polynomial { order: 2 lead: 0.010 spacing: 0.001 } } }\n";
  const auto o = run("stability --study " + path.string() + " --case poly --json");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto j = nlohmann::json::parse(o.output.substr(o.output.find('{')));
  EXPECT_EQ(j["input"]["dofs"], 3);
  EXPECT_TRUE(j["compensated_loop"]["analysed"].get<bool>()) << o.output;
  EXPECT_TRUE(j["compensated_loop"]["stable"].get<bool>()) << o.output;
  EXPECT_NE(j["compensated_loop"]["verdict"].get<std::string>().find("modal approximation"),
            std::string::npos)
      << o.output;
  // Beside it, the uncompensated 10 ms: past the frame's 8.45 ms (the coupled analysis; the
  // characteristic equation det(K_N - M w^2 + i w C + k e^{-i w tau} b b^T) = 0 solved apart
  // gives 8.451 ms, the modal approximation 8.54 ms).
  EXPECT_NE(j["compensated_loop"]["verdict"].get<std::string>().find(
                "uncompensated, lag 10 ms against a critical delay of 8.45 ms"),
            std::string::npos)
      << o.output;
}

// `rths stability --study` on a predicted case of several DOFs (the consortium's frame, its storey
// damper k 3e5 N/m, c 1e4 N s/m between floors 1 and 2): the coupled loop's verdict with the
// link's critical lag, exit 1 when the case's lag is past it, 0 when the model holds every lag.
TEST(MatrixStructureCli, StabilityOfAPredictedCaseOnSeveralDofsIsTheCoupledLoops) {
  const auto path = scratch() / "frame3_damper.textproto";
  std::ofstream(path)
      << "name: \"frame3_damper\" structure { matrices { "
         "mass { rows: 3 values: [1000, 0, 0, 0, 1000, 0, 0, 0, 800] } "
         "stiffness { rows: 3 values: [4e6, -2e6, 0, -2e6, 3.5e6, -1.5e6, 0, -1.5e6, 1.5e6] } } "
         "damping { rayleigh { zeta: 0.03 } } }\n"
      << "motion { path: \"" << kMotion << "\" }\n"
      << "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_dofs { dof: 2 from_dof: 1 stiffness: 3e5 damping: 1e4 } }\n"
         "cases { name: \"reference\" }\n"
         "cases { name: \"exact_60ms\" delay { shift { delay: 0.060 } } "
         "force_predictor { fixed_model: true } }\n"
         "cases { name: \"no_dashpot_60ms\" delay { shift { delay: 0.060 } } "
         "force_predictor { fixed_model: true damping: 1e-6 } }\n";
  const auto exact = run("stability --study " + path.string() + " --case exact_60ms");
  EXPECT_EQ(exact.exit_code, 0) << exact.output;
  EXPECT_NE(exact.output.find("stable for every lag"), std::string::npos) << exact.output;
  EXPECT_EQ(exact.output.find("SDOF only"), std::string::npos) << exact.output;
  const auto past = run("stability --study " + path.string() + " --case no_dashpot_60ms");
  EXPECT_EQ(past.exit_code, 1) << past.output;
  EXPECT_NE(past.output.find("critical lag 9.43 ms against the case's 60 ms: PAST it"),
            std::string::npos)
      << past.output;
  const auto json = run("stability --study " + path.string() + " --case no_dashpot_60ms --json");
  EXPECT_EQ(json.exit_code, 1) << json.output;
  // The JSON, then the reason of the exit on the next line.
  const std::size_t from = json.output.find('{'), to = json.output.rfind("\n}");
  ASSERT_TRUE(from != std::string::npos && to != std::string::npos) << json.output;
  const auto j = nlohmann::json::parse(json.output.substr(from, to + 2 - from));
  EXPECT_TRUE(j["compensated_loop"]["analysed"].get<bool>()) << json.output;
  EXPECT_FALSE(j["compensated_loop"]["stable"].get<bool>()) << json.output;
}

// A chain of n floors in Matrix Market files under `dir` (diagonal M, tridiagonal K).
void write_chain(const std::filesystem::path& dir, int n) {
  std::ofstream mass(dir / "mass.mtx"), stiffness(dir / "stiffness.mtx");
  mass << "%%MatrixMarket matrix coordinate real symmetric\n" << n << ' ' << n << ' ' << n << '\n';
  stiffness << "%%MatrixMarket matrix coordinate real symmetric\n"
            << n << ' ' << n << ' ' << 2 * n - 1 << '\n';
  for (int i = 1; i <= n; ++i) {
    mass << i << ' ' << i << ' ' << 1e5 << '\n';
    stiffness << i << ' ' << i << ' ' << (i < n ? 8e10 : 4e10) << '\n';
    if (i > 1) stiffness << i << ' ' << i - 1 << ' ' << -4e10 << '\n';
  }
}

// `rths run` on a model held sparse with modal_zeta: the modes kept are stated before the run,
// and the summary ends with the set-up time and the per-step cost, R / N of the cases' run.
TEST(MatrixStructureCli, RunStatesSparseModalDampingAndPrintsItsSetUpAndPerStepCost) {
  const auto dir = scratch() / "chain";
  std::filesystem::create_directories(dir);
  write_chain(dir, 150);
  std::ofstream(dir / "chain.textproto")
      << "name: \"chain\" structure { matrices { mass { file: \"mass.mtx\" } stiffness { file: "
         "\"stiffness.mtx\" } } damping { modal_zeta: 0.05 } }\n motion { path: \""
      << kMotion << "\" duration: 0.5 }\n integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
      << " substructuring { experimental_dofs { dof: 1 stiffness: 1e10 } }\n"
         " cases { name: \"reference\" } cases { name: \"lag\" delay { shift { delay: 0.002 } } "
         "}\n";
  const auto o = run("run " + (dir / "chain.textproto").string() + " --no-plots --out " +
                     (dir / "out").string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("modal_zeta on 150 DOFs held sparse: zeta 0.05 in the lowest"),
            std::string::npos)
      << o.output;
  const auto at = o.output.find("timing: set-up ");
  ASSERT_NE(at, std::string::npos) << o.output;
  double setup = 0, run_s = 0, per_step = 0;
  int cases = 0;
  long steps = 0;
  ASSERT_EQ(std::sscanf(o.output.c_str() + at,
                        "timing: set-up %lf s; %d cases, %ld steps in %lf s: %lf us a step", &setup,
                        &cases, &steps, &run_s, &per_step),
            5)
      << o.output.substr(at);
  EXPECT_GT(setup, 0.0);
  EXPECT_GT(run_s, 0.0);
  EXPECT_GT(per_step, 0.0);
  EXPECT_EQ(cases, 2);
  std::ifstream csv(dir / "out" / "results.csv");
  std::string line;
  long rows = -1;  // the header
  while (std::getline(csv, line))
    if (!line.empty()) ++rows;
  EXPECT_EQ(steps, 2 * rows) << "every case's steps, one row each in results.csv";
  EXPECT_NEAR(per_step, 1e6 * run_s / static_cast<double>(steps), 1e-4 * per_step);
}

// `rths run --help` names and defines the criteria a benchmark study is judged by.
TEST(MatrixStructureCli, RunHelpDefinesTheBenchmarkCriteria) {
  const auto o = run("run --help");
  EXPECT_EQ(o.exit_code, 0) << o.output;
  for (const char* text : {"J1 (ms)", "J2 (%)   100 std(x_m - x_t) / std(x_t)", "J9 (%)"})
    EXPECT_NE(o.output.find(text), std::string::npos) << text << "\n" << o.output;
}

// Issue 39's 3-DOF frame with 10 ms of lag, 17 % past its 8.54 ms critical delay: its envelope
// grows to the end of the record while its peak stays under 10x the lag-free run's. `rths run`
// reports it diverging with its growth rate and exits 1; --allow-unstable exits 0.
TEST(MatrixStructureCli, AFramePastItsCriticalDelayThatGrowsIsDivergingAndExitsOne) {
  const auto path = scratch() / "frame3.textproto";
  std::ofstream(path)
      << "name: \"frame3\" structure { matrices { "
         "mass { rows: 3 values: [1000, 0, 0, 0, 1000, 0, 0, 0, 800] } "
         "stiffness { rows: 3 values: [4e6, -2e6, 0, -2e6, 3.5e6, -1.5e6, 0, -1.5e6, 1.5e6] } "
         "damping { rows: 3 values: [2275.816349, -809.9103853, 0, -809.9103853, 2073.338753, "
         "-607.432789, 0, -607.432789, 1132.229252] } } }\n"
      << "motion { path: \"" << kMotion << "\" }\n"
      << "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_dofs { dof: 1 stiffness: 0.5e6 } }\n"
         "cases { name: \"reference\" } cases { name: \"lag_10ms\" delay { shift { delay: 0.010 "
         "} } }\n";
  const auto out = scratch() / "frame3";
  auto o = run("run " + path.string() + " --no-plots --out " + out.string());
  EXPECT_EQ(o.exit_code, 1) << o.output;
  EXPECT_NE(o.output.find("diverging"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("doubling every"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("'lag_10ms' is diverging"), std::string::npos) << o.output;
  o = run("run " + path.string() + " --no-plots --allow-unstable --out " + out.string());
  EXPECT_EQ(o.exit_code, 0) << o.output;
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
  // Every draw is kept: one row each, the plant drawn and every criterion named with its unit.
  std::ifstream csv(dir / "a" / "benchmark_perturbed.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("draw,beta1,beta2_1_per_s,a3_1_per_s,k_e_N_per_m,sample_controller_J1_ms,"
                         "sample_controller_J2_pct,",
                         0),
            0u)
      << header;
  int rows = 0;
  while (std::getline(csv, line))
    if (!line.empty()) ++rows;
  EXPECT_EQ(rows, 3);
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
