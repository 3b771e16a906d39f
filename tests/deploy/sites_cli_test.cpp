// `rths sites` as a user sees it: exit codes and messages (2 bad config, 3 no namespaces).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "deploy/netns.h"
#include "tests/support/dds_scope.h"

#include "util/process.h"

namespace rths::deploy {

using util::run_command;
using util::tool_available;
namespace {

const std::string kRths = std::string(RTHS_BINARY_DIR) + "/cli/rths";
const std::string kConfig = std::string(RTHS_SOURCE_DIR) + "/configs/sites_paper_frame.textproto";

TEST(SitesCli, CheckAcceptsTheShippedConfig) {
  const auto result = util::run_command({kRths, "sites", kConfig, "--check"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("3 processes on 3 sites"), std::string::npos) << result.output;
}

TEST(SitesCli, DomainOverridesTheConfigsAndIsCheckedLikeLaunchs) {
  const auto result = util::run_command({kRths, "sites", kConfig, "--check", "--domain", "77"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("DDS domain 77"), std::string::npos) << result.output;
  const auto shipped = util::run_command({kRths, "sites", kConfig, "--check"});
  EXPECT_NE(shipped.output.find("DDS domain 101"), std::string::npos) << shipped.output;
  const auto bad = util::run_command({kRths, "sites", kConfig, "--check", "--domain", "300"});
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--domain"), std::string::npos) << bad.output;
}

// --view takes launch's HOST:PORT and --view-stop needs it: both refused before anything starts.
TEST(SitesCli, RefusesABadViewAddressAndAControlRoomWithoutAView) {
  const auto bad = util::run_command({kRths, "sites", kConfig, "--check", "--view", "lab-pc:80"});
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("host 'lab-pc' is not an IPv4 address"), std::string::npos)
      << bad.output;
  const auto alone = util::run_command({kRths, "sites", kConfig, "--check", "--view-stop"});
  EXPECT_EQ(alone.exit_code, 2) << alone.output;
  EXPECT_NE(alone.output.find("--view-stop needs --view HOST:PORT"), std::string::npos)
      << alone.output;
  const auto ok = util::run_command(
      {kRths, "sites", kConfig, "--check", "--view", "127.0.0.1:0", "--view-stop"});
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

// --probe: each link measured over DDS in the namespaces for the given seconds (a lockstep
// study's too, in real time), its figures and the verdict against the critical round trip; a
// probe shorter than 0.5 s is refused.
TEST(SitesCli, ProbeStatesEachLinksFiguresAndTheVerdict) {
  if (const auto reason = deploy::namespace_support()) GTEST_SKIP() << *reason;
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_sites_probe_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "study.textproto")
      << "name: \"probe\"\nstructure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 "
         "} }\nmotion { path: \"" RTHS_SOURCE_DIR
         "/data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: 5 }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
         "cases { name: \"lag_shift_4ms\" delay { shift { delay: 0.004 } } }\n";
  std::ofstream(dir / "sites.textproto")
      << "study: \"study.textproto\"\ncase_name: \"lag_shift_4ms\"\nclock: LOCKSTEP\n"
      << "domain_id: " << test::scope_dds_to_this_test() << "\n"
      << "subnet: \"10.231.203\"\ntimeout: 60\n"
         "sites { name: \"integrator\" node_ids: [0, 1] }\nsites { name: \"lab\" node_ids: 2 }\n"
         "links { node_id: 2 to_node { one_way_delay: 0.002 } from_node { one_way_delay: 0.002 } "
         "}\n"
         "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR } "
         "start_timeout: 20 }\n";
  const auto probe =
      util::run_command({kRths, "sites", (dir / "sites.textproto").string(), "--probe", "1",
                         "--bin-dir", RTHS_BINARY_DIR, "--out", (dir / "out").string()},
                        std::chrono::seconds(60));
  EXPECT_EQ(probe.exit_code, 0) << probe.output;
  EXPECT_NE(probe.output.find("link to node 2 (site lab): round trip median 4."),
            std::string::npos)
      << probe.output;  // the 4 ms the node injects, and the exchange
  EXPECT_NE(probe.output.find("[uncompensated]; answer age not judged (a lockstep study waits for "
                              "each answer): the study can take it"),
            std::string::npos)
      << probe.output;
  const auto short_probe =
      util::run_command({kRths, "sites", (dir / "sites.textproto").string(), "--probe", "0.1"});
  EXPECT_EQ(short_probe.exit_code, 2) << short_probe.output;
  std::filesystem::remove_all(dir);
}

std::string read(const std::filesystem::path& path);

// `rths sites` takes `rths launch`'s platform flags: once it printed "run anyway with
// --accept-platform" and then refused that flag (exit 2).
TEST(SitesCli, TakesLaunchsPlatformFlags) {
  const auto result = util::run_command(
      {kRths, "sites", kConfig, "--check", "--accept-platform", "--platform-seconds", "0.5"});
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("sites config ok"), std::string::npos) << result.output;
}

// A real-time deployment this machine cannot keep (a fail-safe window of one 1 ms step: any
// stall passes it) is refused as `rths launch` refuses it: the platform check first, exit 3,
// the fix named, nothing started (no namespace, no record, no platform.json). Once the
// coordinator refused it at a site and `sites` called that a failed run (exit 1).
TEST(SitesCli, APlatformRefusalExitsThreeBeforeAnythingStarts) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_sites_platform_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "sites.textproto")
      << "study: \"" << RTHS_SOURCE_DIR << "/configs/paper_frame.textproto\"\n"
      << "case_name: \"reference\"\nclock: REAL_TIME\nduration: 1\n"
      << "sites { name: \"integrator\" node_ids: 0 }\nsites { name: \"hpc\" node_ids: 1 }\n"
      << "sites { name: \"lab_b\" node_ids: 2 }\n"
      << "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR "
         "} answer_window_ms: 1 command_watchdog_ms: 1 }\n";
  const auto refused =
      util::run_command({kRths, "sites", (dir / "sites.textproto").string(), "--platform-seconds",
                         "0.2", "--out", (dir / "out").string()});
  EXPECT_EQ(refused.exit_code, 3) << refused.output;
  EXPECT_NE(refused.output.find("refusing to start"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("--accept-platform runs anyway"), std::string::npos)
      << refused.output;
  EXPECT_NE(refused.output.find("answer_window_ms: "), std::string::npos) << refused.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "reference.rthsrec"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "platform.json"));
  std::filesystem::remove_all(dir);
}

// Before a run (and with --check): the case's lag plus the network round trip on the actuator
// lab's link, against the critical delay. The shipped distributed frame across sites in real
// time: 7 ms each way + the 14 ms shift = 28 ms, past the frame's 24.2 ms.
TEST(SitesCli, CheckWarnsWhenNetworkAndActuatorLagTogetherPassTheCriticalDelay) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_sites_critical_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& case_name,
                         const std::string& clock) {
    std::ofstream(dir / name)
        << "study: \"" << RTHS_SOURCE_DIR << "/configs/paper_frame_distributed.textproto\"\n"
        << "case_name: \"" << case_name << "\"\nclock: " << clock << "\n"
        << "sites { name: \"integrator\" node_ids: 0 }\nsites { name: \"hpc\" node_ids: 1 }\n"
        << "sites { name: \"lab_b\" node_ids: 2 }\n"
        << "links { node_id: 2 to_node { one_way_delay: 0.007 } from_node { one_way_delay: 0.007 } "
           "}\n";
  };
  write("lagged.textproto", "lag_shift_14ms", "REAL_TIME");
  write("reference.textproto", "reference", "REAL_TIME");
  write("lockstep.textproto", "lag_shift_14ms", "LOCKSTEP");
  const auto lagged =
      util::run_command({kRths, "sites", (dir / "lagged.textproto").string(), "--check"});
  EXPECT_EQ(lagged.exit_code, 0) << lagged.output;
  EXPECT_NE(lagged.output.find(
                "rths: warning: case 'lag_shift_14ms': network round trip 14 ms injected on the "
                "actuator lab's link + actuator lag 14 ms (the case's delay stages): lag 28 ms"),
            std::string::npos)
      << lagged.output;
  EXPECT_NE(lagged.output.find("PAST it by"), std::string::npos) << lagged.output;
  const auto reference =
      util::run_command({kRths, "sites", (dir / "reference.textproto").string(), "--check"});
  EXPECT_EQ(reference.output.find("warning"), std::string::npos) << reference.output;
  // Lockstep pairs every command with its own answer: the network lag does not enter.
  const auto lockstep =
      util::run_command({kRths, "sites", (dir / "lockstep.textproto").string(), "--check"});
  EXPECT_EQ(lockstep.output.find("warning"), std::string::npos) << lockstep.output;
  std::filesystem::remove_all(dir);
}

// `--check` refuses what no run could mean, each named, before anything runs: an unknown clock
// (proto3 keeps the number), a duration or timeout that is no time (NaN fails every comparison,
// so it once read as the default and the run went ahead), a subnet the sites cannot be given.
TEST(SitesCli, CheckRefusesNonFiniteAndOutOfRangeFieldsAndALoopbackSubnet) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_sites_fields_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::vector<std::pair<std::string, std::string>> cases{
      {"clock: -1", "clock -1 is not STUDY (0), LOCKSTEP (1) or REAL_TIME (2)"},
      {"duration: nan", "duration nan s is not a time (finite, >= 0; 0 = the default)"},
      {"timeout: nan", "timeout nan s is not a time (finite, >= 0; 0 = the default)"},
      {"timeout: inf", "timeout inf s is not a time"},
      {"duration: -1", "duration -1 s is not a time"},
      {"subnet: \"127.0.0\"", "subnet '127.0.0' is not a unicast network for the sites"},
      {"subnet: \"224.1.2\"", "subnet '224.1.2' is not a unicast network for the sites"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto path = dir / ("bad_" + std::to_string(i) + ".textproto");
    std::ofstream(path) << "study: \"" << RTHS_SOURCE_DIR
                        << "/configs/paper_frame_distributed.textproto\"\n"
                        << cases[i].first << "\nsites { name: \"integrator\" node_ids: 0 }\n"
                        << "sites { name: \"hpc\" node_ids: 1 }\nsites { name: \"lab_b\" "
                        << "node_ids: 2 }\n";
    const auto result = util::run_command({kRths, "sites", path.string(), "--check"});
    EXPECT_EQ(result.exit_code, 2) << cases[i].first << ": " << result.output;
    EXPECT_NE(result.output.find(cases[i].second), std::string::npos)
        << cases[i].first << ": " << result.output;
  }
  std::filesystem::remove_all(dir);
}

std::string read(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> header_of(const std::filesystem::path& csv) {
  const std::string text = read(csv);
  std::istringstream line(text.substr(0, text.find('\n')));
  std::vector<std::string> cells;
  for (std::string cell; std::getline(line, cell, ',');) cells.push_back(cell);
  return cells;
}

// `rths sites` writes its results as `rths run` does: the same columns for its case (plus lag per
// link), the same step count, plots, and the comparison with the lag-free in-process reference.
TEST(SitesCli, WritesRunsColumnsPlotsAndComparesWithTheLagFreeReference) {
  if (const auto reason = deploy::namespace_support()) GTEST_SKIP() << *reason;
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_sites_results_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  // The paper's frame, 0.3 s of the record; `run` gets only the case that sites runs.
  const auto study = [](const std::string& cases) {
    return "name: \"paper_frame\"\n"
           "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
           "motion { path: \"" +
           std::string(RTHS_SOURCE_DIR) +
           "/data/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: 0.3 }\n"
           "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
           "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n" +
           cases;
  };
  const std::string lagged =
      "cases { name: \"lag_shift_14ms\" delay { shift { delay: 0.014 } } }\n";
  // The study's own reference is the lagged case: sites must compare with the lag-free run instead.
  std::ofstream(dir / "study.textproto")
      << study("cases { name: \"reference\" }\n" + lagged + "reference_case: \"lag_shift_14ms\"\n");
  std::ofstream(dir / "single.textproto") << study(lagged);
  std::ofstream(dir / "sites.textproto")
      << "study: \"study.textproto\"\ncase_name: \"lag_shift_14ms\"\nclock: LOCKSTEP\n"
         "timeout: 60\nsites { name: \"integrator\" node_ids: 0 }\nsites { name: \"lab\" node_ids: "
         "[1, 2] }\n"
         "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR } "
         "start_timeout: 20 }\n";
  const auto sites =
      util::run_command({kRths, "sites", (dir / "sites.textproto").string(), "--domain",
                         std::to_string(test::scope_dds_to_this_test()), "--bin-dir",
                         RTHS_BINARY_DIR, "--out", (dir / "sites").string()},
                        std::chrono::seconds(120));
  ASSERT_EQ(sites.exit_code, 0) << sites.output;
  EXPECT_NE(sites.output.find("against the lag-free in-process reference"), std::string::npos)
      << sites.output;
  // The record is named as `rths launch` names it; "written" names the figures drawn.
  EXPECT_TRUE(std::filesystem::exists(dir / "sites" / "lag_shift_14ms.rthsrec"));
  EXPECT_FALSE(std::filesystem::exists(dir / "sites" / "record.pb"));
  EXPECT_NE(sites.output.find("displacement.png/.svg, force_displacement.png/.svg"),
            std::string::npos)
      << sites.output;
  EXPECT_NE(sites.output.find("links_lag_shift_14ms.png/.svg, summary.txt"), std::string::npos)
      << sites.output;
  // The DDS line's counts say what they count: lockstep answers every step, once.
  EXPECT_NE(sites.output.find("measured on 299 answers, each at the first step that applied it, "
                              "of 299 accepted"),
            std::string::npos)
      << sites.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "sites" / "displacement.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "sites" / "links_lag_shift_14ms.png"));
  EXPECT_NE(sites.output.find("sites: 100% (1/1 runs"), std::string::npos) << sites.output;
  // Links by role and by the site the sites config names, not by node id.
  const std::string lag_plot = read(dir / "sites" / "links_lag_shift_14ms.svg");
  for (const char* label : {"actuator lab \"lab\": round trip, measured",
                            "numerical site \"lab\": round trip, injected"})
    EXPECT_NE(lag_plot.find(label), std::string::npos) << label;

  const auto ran = util::run_command({kRths, "run", (dir / "single.textproto").string(),
                                      "--no-plots", "--json", "--out", (dir / "run").string()});
  ASSERT_EQ(ran.exit_code, 0) << ran.output;
  std::vector<std::string> sites_header, lag_columns;
  for (const auto& cell : header_of(dir / "sites" / "results.csv"))
    (cell.find("_node") == std::string::npos ? sites_header : lag_columns).push_back(cell);
  EXPECT_EQ(sites_header, header_of(dir / "run" / "results.csv"));
  EXPECT_EQ(lag_columns.size(), 4u);  // injected and round trip, two links
  const auto summary = nlohmann::json::parse(read(dir / "sites" / "summary.json"));
  const auto in_process = nlohmann::json::parse(ran.output.substr(ran.output.find('{')));
  EXPECT_EQ(summary["reference"], "the lag-free in-process reference");
  EXPECT_EQ(summary["cases"][0]["steps"], in_process["cases"][0]["steps"]);
  // Lockstep across sites equals the in-process run; its reference is the lag-free run, not itself.
  EXPECT_GT(summary["cases"][0]["nrmse_pct"].get<double>(), 1.0);
  EXPECT_EQ(summary["cases"][0]["max_difference_from_in_process_m"].get<double>(), 0.0);
  std::filesystem::remove_all(dir);
}

TEST(SitesCli, BadConfigExitsTwoNamingTheFile) {
  const auto missing = util::run_command({kRths, "sites", "/nonexistent/sites.textproto"});
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("/nonexistent/sites.textproto"), std::string::npos);
}

// Without the right to make namespaces (here: the same command as user nobody, which needs root
// to arrange), the command says so and exits 3 before touching anything.
TEST(SitesCli, NoNamespacePermissionExitsThreeSayingWhy) {
  if (::geteuid() != 0 || !util::tool_available("setpriv")) {
    GTEST_SKIP() << "needs root and setpriv to run the command as an unprivileged user";
  }
  const auto copy = std::filesystem::temp_directory_path() / "rths_sites_cli_test";
  std::filesystem::create_directories(copy);
  std::filesystem::permissions(copy, std::filesystem::perms::all);
  const auto result =
      util::run_command({"setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", kRths,
                         "sites", kConfig, "--out", copy.string()});
  EXPECT_EQ(result.exit_code, 3) << result.output;
  EXPECT_NE(result.output.find("network namespaces are not permitted"), std::string::npos)
      << result.output;
  std::filesystem::remove_all(copy);
}

}  // namespace
}  // namespace rths::deploy
