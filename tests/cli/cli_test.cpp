// End-to-end checks of the `rths` binary: exit codes, JSON, files, and the paper's findings.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>

namespace {

const std::string kRths = RTHS_EXECUTABLE;
const std::filesystem::path kSource = RTHS_SOURCE_DIR;
const std::filesystem::path kData = RTHS_SHARED_DATA_DIR;

struct Outcome {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

Outcome run(const std::string& arguments) {
  Outcome outcome;
  FILE* pipe = popen((kRths + " " + arguments + " 2>&1").c_str(), "r");
  if (!pipe) return outcome;
  std::array<char, 4096> buffer{};
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) outcome.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return outcome;
}

std::filesystem::path scratch(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("rths_cli_test_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

nlohmann::json json_of(const Outcome& o) {
  const auto start = o.output.find('{');
  return nlohmann::json::parse(o.output.substr(start == std::string::npos ? 0 : start));
}

TEST(CliTest, SdofJsonAndCsvShowLagEnlargingTheResponse) {
  const auto dir = scratch("sdof");
  const Outcome o = run("sdof --period 0.5 --zeta 0.05 --exp-fraction 0.3333 --dt 0.001 --delay 0.014 "
                        "--delay-model shift --motion " + (kData / "ground_motions/RSN175_IMPVALL.H_H-E12140.AT2").string() +
                        " --json --out " + (dir / "sdof.csv").string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const nlohmann::json j = json_of(o);
  EXPECT_GT(j["peak_delayed_m"].get<double>(), j["peak_reference_m"].get<double>());
  EXPECT_GT(j["nrmse"].get<double>(), 0.1);
  EXPECT_GT(j["paper_eq2_as_printed"].get<double>(), 0.0);
  std::ifstream csv(dir / "sdof.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "time_s,u_reference_m,u_delayed_m");
  std::size_t rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, 39070u);  // 7814 samples at 5 ms resampled to 1 ms over the same duration
}

TEST(CliTest, PaperFrameRunShowsLagLargerAndPrintedEq1Smaller) {
  const auto dir = scratch("run");
  const Outcome o = run("run " + (kSource / "configs/paper_frame.textproto").string() + " --json --out " + dir.string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const nlohmann::json j = json_of(o);
  std::map<std::string, double> peak;
  for (const auto& c : j["cases"]) peak[c["name"].get<std::string>()] = c["peak_displacement_m"].get<double>();
  EXPECT_GT(peak.at("lag_shift_14ms"), peak.at("reference"));
  EXPECT_GT(peak.at("eq1_lag_14ms"), peak.at("reference"));
  EXPECT_LT(peak.at("eq1_as_printed_14ms"), peak.at("reference"));
  for (const char* file : {"results.csv", "summary.json", "summary.txt", "displacement.png", "force_displacement.png"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / file)) << file;
  }
}

TEST(CliTest, StabilityJsonNamesBothCriticalDelays) {
  const Outcome o = run("stability --period 0.5 --zeta 0.05 --exp-fraction 1 --dt 0.001 --json");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const nlohmann::json j = json_of(o);
  const double continuous = j["continuous"]["critical_delay_s"].get<double>();
  const double discrete = j["discrete"]["first_unstable_delay_s"].get<double>();
  EXPECT_GT(continuous, 0.005);
  EXPECT_LT(continuous, 0.012);
  EXPECT_NEAR(discrete, continuous, 0.003);
}

TEST(CliTest, BadInputExitsTwoWithAMessageNamingTheProblem) {
  const auto dir = scratch("bad");
  std::ofstream(dir / "bad.textproto") << "name: \"x\"\nstructure { sdof { period: 0.5 colour: 3 } }\n";
  Outcome o = run("run " + (dir / "bad.textproto").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("bad.textproto:2:"), std::string::npos) << o.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "results.csv"));

  o = run("sdof --motion " + (dir / "missing.AT2").string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("missing.AT2"), std::string::npos) << o.output;

  o = run("sdof --period -1 --motion x");
  EXPECT_EQ(o.exit_code, 2) << o.output;

  o = run("sdof --period 0.05 --dt 0.02 --delay 0 --motion " + (kData / "ground_motions/IELC180.AT2").string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("unstable"), std::string::npos) << o.output;
}

}  // namespace
