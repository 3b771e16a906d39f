// End-to-end checks of what `rths` reads and where it writes: a motion's units (its file's
// header, the flag, the config), files that are not motions, and output folders (owned by their
// study, plots of an earlier run kept).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>

#include "tests/cli/cli_support.h"
#include "tests/support/dds_scope.h"

using namespace rths::cli_test;

namespace {

TEST(CliTest, MotionUnitsAreExplicit) {
  const auto dir = scratch("units");
  // El Centro's first seconds as m/s^2 columns.
  std::ofstream(dir / "ms2.txt")
      << "0 0\n0.01 1.2\n0.02 -2.5\n0.03 3.1\n0.04 -1.0\n0.05 0.4\n0.06 0\n";
  Outcome o =
      run("sdof --motion " + (dir / "ms2.txt").string() + " --exp-fraction 0.3333 --delay 0.002");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("--motion-units"), std::string::npos) << o.output;
  o = run("sdof --motion " + (dir / "ms2.txt").string() +
          " --motion-units m/s2 --exp-fraction 0.3333 --delay 0.002 --json");
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(json_of(o)["motion_units"], "m/s2");
}

// An output folder belongs to the study that wrote it: a renamed study that would write there is
// refused unless --force, and --no-plots leaves an earlier run's plots where they are.
TEST(CliTest, AnOutputFolderIsOwnedByItsStudy) {
  const auto dir = scratch("owner");
  const auto study = [&](const std::string& name) {
    const auto path = dir / (name + ".textproto");
    std::ofstream(path) << "name: \"" << name
                        << "\" structure { sdof { period: 0.5 } } motion { path: \"" << kMotion
                        << "\" duration: 2 } substructuring { experimental_fraction: 0.3 } "
                           "cases { name: \"reference\" }\n";
    return path.string();
  };
  const std::string out = " --no-plots --out " + (dir / "out").string();
  ASSERT_EQ(run("run " + study("first") + out).exit_code, 0);
  std::ofstream(dir / "out" / "displacement.png") << "an earlier run's plot";
  std::ofstream(dir / "out" / "actuators_2.png") << "an earlier run's second actuator page";
  const Outcome again = run("run " + study("first") + out);
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "displacement.png"));
  EXPECT_NE(again.output.find("from an earlier run: displacement.png"), std::string::npos)
      << again.output;
  EXPECT_NE(again.output.find("actuators_2.png"), std::string::npos) << again.output;
  const Outcome other = run("run " + study("second") + out);
  EXPECT_EQ(other.exit_code, 2) << other.output;
  EXPECT_NE(other.output.find("holds study 'first'"), std::string::npos) << other.output;
  EXPECT_NE(other.output.find("--force"), std::string::npos) << other.output;
  EXPECT_EQ(run("run " + study("second") + out + " --force").exit_code, 0);
  EXPECT_EQ(run("run " + study("first") + out).exit_code, 2);
}

// A lab's PEER file in cm/s^2 (its header says so) gives the response of its g original; a
// --motion-units that contradicts the header is bad input, naming both.
TEST(CliTest, APeerFileInCmPerS2RunsAsItsGOriginal) {
  const auto dir = scratch("peer_cm");
  std::ifstream in(kMotion);
  std::ofstream cm(dir / "elcentro12_cm.AT2");
  std::string line;
  for (int i = 1; std::getline(in, line); ++i) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (i <= 4) {
      cm << (i == 3 ? "ACCELERATION TIME SERIES IN UNITS OF CM/S/S" : line) << "\n";
      continue;
    }
    std::istringstream values(line);
    for (double g = 0.0; values >> g;) cm << std::setprecision(11) << g * 980.665 << " ";
    cm << "\n";
  }
  cm.close();
  const std::string sdof = "sdof --period 0.5 --exp-fraction 0.3333 --delay 0.002 --json --motion ";
  const Outcome in_g = run(sdof + kMotion);
  const Outcome in_cm = run(sdof + (dir / "elcentro12_cm.AT2").string());
  ASSERT_EQ(in_g.exit_code, 0) << in_g.output;
  ASSERT_EQ(in_cm.exit_code, 0) << in_cm.output;
  EXPECT_EQ(json_of(in_cm)["motion_units"], "cm/s2");
  const auto peak = [](const nlohmann::json& j) { return j["peak_delayed_m"].get<double>(); };
  EXPECT_NEAR(peak(json_of(in_cm)), peak(json_of(in_g)), 1e-9 * peak(json_of(in_g)));
  const Outcome contradicted =
      run(sdof + (dir / "elcentro12_cm.AT2").string() + " --motion-units g");
  EXPECT_EQ(contradicted.exit_code, 2) << contradicted.output;
  EXPECT_NE(contradicted.output.find("header states cm/s2"), std::string::npos)
      << contradicted.output;
}

// A motion that is not a text file of numbers is named for what it is, never as a unit problem,
// and its bytes never reach the terminal raw; a one-column motion takes its step from --motion-dt.
TEST(CliTest, MotionFilesThatAreNotMotionsAreNamedForWhatTheyAre) {
  const auto dir = scratch("motion_files");
  std::ofstream(dir / "empty.txt").close();
  std::ofstream(dir / "binary.bin", std::ios::binary) << std::string(
      "\x7f"
      "ELF\x02\x01\x01\x00\x00\x9b\xff",
      12);
  std::filesystem::create_directories(dir / "folder");
  Outcome o = run("sdof --motion " + (dir / "empty.txt").string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("is empty, not a ground-motion file"), std::string::npos) << o.output;
  o = run("sdof --motion " + (dir / "folder").string());
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("is a directory"), std::string::npos) << o.output;
  for (const std::string units : {"", " --motion-units g"}) {
    o = run("sdof --motion " + (dir / "binary.bin").string() + units);
    EXPECT_EQ(o.exit_code, 2) << o.output;
    EXPECT_NE(o.output.find("holds binary data"), std::string::npos) << o.output;
    EXPECT_EQ(o.output.find("\x7f"
                            "ELF"),
              std::string::npos)
        << "raw bytes printed";
    EXPECT_EQ(o.output.find("carry no unit"), std::string::npos) << o.output;
  }
  std::ofstream(dir / "one.txt") << "0\n0.1\n-0.2\n0.3\n-0.1\n0.05\n0\n0\n";
  o = run("sdof --motion " + (dir / "one.txt").string() + " --motion-units g --dt 0.001");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("--motion-dt"), std::string::npos) << o.output;
  o = run("sdof --motion " + (dir / "one.txt").string() +
          " --motion-units g --motion-dt 0.01 --dt 0.001 --json");
  EXPECT_EQ(o.exit_code, 0) << o.output;
}

TEST(CliTest, RunWithoutPlotsKeepsAnEarlierRunsPlotsAndWritesEveryColumn) {
  const auto dir = scratch("stale");
  std::ofstream(dir / "displacement.png") << "old";
  const Outcome o = run("run " + (kSource / "configs/three_storey_building.textproto").string() +
                        " --no-plots --out " + dir.string());
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "displacement.png"));  // named, not deleted
  EXPECT_NE(o.output.find("from an earlier run: displacement.png"), std::string::npos) << o.output;
  std::ifstream csv(dir / "results.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind(
                "step,time_s,reference_u_floor1_m,reference_u_floor2_m,reference_u_floor3_m,", 0),
            0u)
      << header;
  EXPECT_NE(header.find("_force_act1_N"), std::string::npos) << header;
}

}  // namespace

namespace {

// One check for a study, whichever command runs it: a controller block `launch` refuses is
// refused by `run` and `sites --check` too, with the same message, before anything runs or is
// written; and a case without a name is refused by each.
TEST(CliTest, EveryCommandRefusesTheSameBadStudyWithTheSameMessage) {
  const auto dir = scratch("one_check");
  std::ifstream in(kSource / "configs/paper_frame_controller.textproto");
  std::stringstream text;
  text << in.rdbuf();
  std::string study = text.str();
  const std::string motion = "\"../data/ground_motions/";
  study.replace(study.find(motion), motion.size(), "\"" + (kData / "ground_motions/").string());
  const std::string port = "peer_port: 47211";
  std::string bad_port = study;
  bad_port.replace(bad_port.find(port), port.size(), "peer_port: 0");
  std::ofstream(dir / "bad_port.textproto") << bad_port;
  const std::string expected =
      "deployment.nodes[id 2]: controller.peer_port 0 is not in [1, 65535]";
  for (const std::string command : {"run", "launch"}) {
    const Outcome o = run(command + " " + (dir / "bad_port.textproto").string() +
                          " --no-plots --out " + (dir / ("out_" + command)).string());
    EXPECT_EQ(o.exit_code, 2) << command << ": " << o.output;
    EXPECT_NE(o.output.find(expected), std::string::npos) << command << ": " << o.output;
    EXPECT_FALSE(std::filesystem::exists(dir / ("out_" + command) / "results.csv")) << command;
  }
  std::string unnamed = study;
  const std::string reference = "name: \"reference\"";
  ASSERT_NE(unnamed.find(reference), std::string::npos);
  unnamed.replace(unnamed.find(reference), reference.size(), "name: \"\"");
  std::ofstream(dir / "unnamed.textproto") << unnamed;
  for (const std::string command : {"run", "launch"}) {
    const Outcome o = run(command + " " + (dir / "unnamed.textproto").string() +
                          " --no-plots --out " + (dir / ("unnamed_" + command)).string());
    EXPECT_EQ(o.exit_code, 2) << command << ": " << o.output;
    EXPECT_NE(o.output.find("has no name"), std::string::npos) << command << ": " << o.output;
  }
}

// A file size limit that cuts every record before its first step is the machine's fault: exit 3,
// each case named as stopped before step 1 with the reader's account of the cut record, never
// "compare: an empty history".
TEST(CliTest, LaunchUnderAFileSizeLimitIsAnEnvironmentFault) {
  const auto dir = scratch("fsize");
  const std::string launch =
      kRths + " launch " + (kSource / "configs/paper_frame.textproto").string() +
      " --case reference --domain " + std::to_string(rths::test::scope_dds_to_this_test()) +
      " --no-plots --out " + (dir / "out").string();
  const Outcome o = rths::test::run_command_line("sh -c 'ulimit -f 4; exec " + launch + "'");
  EXPECT_EQ(o.exit_code, 3) << o.output;
  EXPECT_EQ(o.output.find("empty history"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("reference: FAILED, stopped before step 1: "), std::string::npos)
      << o.output;
  EXPECT_NE(o.output.find("truncated after"), std::string::npos) << o.output;
}

}  // namespace
