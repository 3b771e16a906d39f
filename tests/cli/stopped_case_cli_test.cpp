// `rths run`'s outputs survive a case that stops early and a gnuplot that fails: the table and
// summary are always written, "written:" names only the files written, the figures of a stopped
// case end at its stop, and the exit is the cases' (issue 61 item 6).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/cli/cli_support.h"

namespace rths::cli_test {
namespace {

// The paper's frame, 20 s of El Centro, all of it experimental; `cases` and `extra` appended.
std::filesystem::path write_study(const std::filesystem::path& dir, const std::string& cases,
                                  const std::string& extra = "") {
  const auto path = dir / "study.textproto";
  std::ofstream(path) << "name: \"stopped\"\n"
                      << "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 "
                         "} }\nmotion { path: \""
                      << kMotion
                      << "\" duration: 20 }\nintegrator { dt: 0.001 }\n"
                         "substructuring { experimental_fraction: 1 }\n"
                      << cases << extra;
  return path;
}

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// 30 ms of lag runs away; the 5 cm limit stops it at about 4 s, before the reference's strongest
// second (16-17 s). Before: gnuplot found no point in that case's tracking zoom, no figure was
// written, nor the summary, and `run` exited 3 with results.csv alone.
TEST(StoppedCase, RunDrawsAStoppedCaseToItsStopWritesEverythingAndExitsAsItsCases) {
  const auto dir = scratch("stopped_case");
  const auto study = write_study(dir,
                                 "cases { name: \"reference\" }\ncases { name: \"lag_30ms\" "
                                 "delay { shift { delay: 0.030 } } expect_unstable: true }\n",
                                 "deployment { limits { max_displacement: 0.05 } }\n");
  const Outcome ran = run("run " + study.string() + " --out " + (dir / "out").string());
  EXPECT_EQ(ran.exit_code, 1) << ran.output;  // a tripped limit fails the run, as --no-plots
  EXPECT_NE(ran.output.find("case 'lag_30ms': limit tripped"), std::string::npos) << ran.output;
  EXPECT_NE(ran.output.find("results.csv, displacement.png/.svg, force_displacement.png/.svg, "
                            "tracking.png/.svg, summary.txt, summary.json"),
            std::string::npos)
      << ran.output;
  for (const char* file : {"results.csv", "summary.txt", "summary.json", "displacement.png",
                           "displacement.svg", "tracking.png", "tracking.svg"})
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / file)) << file;
  const std::string tracking = read(dir / "out" / "tracking.svg");
  EXPECT_NE(tracking.find("zoom: lag_30ms over 1 s up to its stop"), std::string::npos);
  EXPECT_NE(tracking.find(">limit tripped<"), std::string::npos);  // the line at its stop
  EXPECT_NE(read(dir / "out" / "displacement.svg").find(">lag_30ms (limit tripped at t = "),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

// Without gnuplot the figures fail: a warning says so, the table and summary are written,
// "written:" names no figure, and the exit is the cases' (0 here), not 3. Before: exit 3, no
// summary.
TEST(StoppedCase, FiguresThatFailLeaveTheTableAndSummaryAndTheCasesExit) {
  const auto dir = scratch("no_gnuplot");
  const auto study =
      write_study(dir,
                  "cases { name: \"reference\" }\ncases { name: \"lag_2ms\" delay { shift { delay: "
                  "0.002 } } }\n");
  const Outcome ran =
      rths::test::run_command_line("PATH=" + dir.string() + " " + kRths + " run " + study.string() +
                                   " --out " + (dir / "out").string());
  EXPECT_EQ(ran.exit_code, 0) << ran.output;
  EXPECT_NE(ran.output.find("rths: warning: no figure drawn (the table and summary are written)"),
            std::string::npos)
      << ran.output;
  EXPECT_NE(ran.output.find("written: " + (dir / "out" / "results.csv").string() +
                            ", summary.txt, summary.json"),
            std::string::npos)
      << ran.output;
  for (const char* file : {"results.csv", "summary.txt", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / file)) << file;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "displacement.png"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::cli_test
