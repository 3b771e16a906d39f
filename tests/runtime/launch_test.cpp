// `rths launch` and `rths export` end to end (the real binary; on the shared DDS domain, each test
// on topics of its own: tests/support/dds_scope.h).
#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "runtime/node/schema.h"
#include "test_support.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

struct Output {
  int code;
  std::string out;
};

Output run(const std::string& command) {
  Output o{-1, ""};
  FILE* pipe = popen((command + " 2>/dev/null").c_str(), "r");
  if (!pipe) return o;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) o.out += buffer;
  const int status = pclose(pipe);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

const std::string kRths = std::string(RTHS_BINARY_DIR) + "/cli/rths";

// A launched study's deployment: the shared DDS domain, with this test's topics.
std::string scoped_deployment() {
  return "deployment { domain_id: " + std::to_string(test::scope_dds_to_this_test()) + " }";
}

TEST(Launch, RunsEveryCaseAndWritesRecordsResultsAndASummary) {
  const auto dir = test::scratch_dir("launch_cli");
  const auto config = test::write_config(dir, test::paper_frame_study(1.5, scoped_deployment()));
  const auto out = dir / "out";
  const Output o = run(kRths + " launch " + config.string() + " --case reference --case " +
                       "lag_shift_14ms --no-plots --json --bin-dir " + RTHS_BINARY_DIR + " --out " +
                       out.string());
  ASSERT_EQ(o.code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_EQ(j["cases"].size(), 2u);
  EXPECT_EQ(j["cases"][0]["status"], "completed");
  EXPECT_EQ(j["reference"], "the lag-free in-process reference");
  EXPECT_EQ(j["cases"][0]["nrmse_pct"].get<double>(), 0.0);  // no delay: the lag-free run itself
  EXPECT_GT(j["cases"][1]["nrmse_pct"].get<double>(), 1.0);
  EXPECT_GT(j["cases"][1]["links"]["2"]["round_trip_median_s"].get<double>(), 0.0);
  // launch itself checks the lockstep runs against the in-process simulation.
  EXPECT_EQ(j["cases"][0]["max_difference_from_in_process_m"].get<double>(), 0.0);
  EXPECT_EQ(j["cases"][1]["max_difference_from_in_process_m"].get<double>(), 0.0);
  const auto record = runtime::read_record(out / "lag_shift_14ms.rthsrec");
  test::expect_record_equals(record,
                             test::reference_result(test::read_file(config), "lag_shift_14ms"));
  EXPECT_TRUE(std::filesystem::exists(out / "results.csv"));
  EXPECT_TRUE(std::filesystem::exists(out / "summary.txt"));
  EXPECT_TRUE(std::filesystem::exists(out / "logs" / "reference" / "coordinator.log"));
}

// A stranger tries to take node 1's place from its announcement on (tests/support's rths_rogue,
// takeover: ANNOUNCE and READY as node 1, then an answer to every command) while `rths launch`
// runs a case with a delay stage. launch's run secret authenticates every message, so the
// stranger's are dropped unread: the run completes equal to the in-process run, and the secret
// appears in no log.
TEST(Launch, AStrangersTakeoverIsDroppedAndTheSecretIsInNoLog) {
  runtime::ensure_dds_config();  // the stranger on the loopback DDS the launched processes use
  const auto dir = test::scratch_dir("launch_takeover");
  // Long enough (about a second of lockstep) for the stranger to learn the run id and attack.
  const auto config = test::write_config(dir, test::paper_frame_study(10, scoped_deployment()));
  const auto out = dir / "out";
  util::ChildProcess rogue(test::program("rths_rogue", "tests/support"),
                           {"--domain", std::to_string(test::kSharedDomain), "--seconds", "60",
                            "--mode", "takeover", "--every", "1"},
                           dir / "rogue.log");
  std::this_thread::sleep_for(std::chrono::seconds(1));  // discovered before the nodes announce
  const Output o = run(kRths + " launch " + config.string() + " --case lag_shift_14ms " +
                       "--no-plots --bin-dir " + RTHS_BINARY_DIR + " --out " + out.string());
  rogue.terminate();
  const std::string rogue_log = test::read_file(dir / "rogue.log");
  ASSERT_EQ(o.code, 0) << o.out << rogue_log;
  EXPECT_NE(rogue_log.find("ANNOUNCE + READY as node 1: "), std::string::npos) << rogue_log;
  const auto record = runtime::read_record(out / "lag_shift_14ms.rthsrec");
  ASSERT_NE(record.footer(), nullptr);
  EXPECT_EQ(record.footer()->status(), "completed");
  test::expect_record_equals(record,
                             test::reference_result(test::read_file(config), "lag_shift_14ms"));
  const std::string log = test::read_file(out / "logs" / "lag_shift_14ms" / "coordinator.log");
  EXPECT_NE(log.find("dropped unread; newest: kind "), std::string::npos) << log;
  // The footer counts the drops, and the summary and `rths export` say so.
  EXPECT_GT(record.footer()->counters().unauthenticated(), 0u);
  EXPECT_NE(o.out.find(", unauthenticated "), std::string::npos) << o.out;
  const Output exported = run(kRths + " export " + (out / "lag_shift_14ms.rthsrec").string() +
                              " --csv " + (dir / "exported.csv").string());
  EXPECT_EQ(exported.code, 0) << exported.out;
  EXPECT_NE(exported.out.find(" messages dropped unauthenticated: coordinator "), std::string::npos)
      << exported.out;
  const std::regex secret("[0-9a-f]{64}");
  for (const auto& entry : std::filesystem::recursive_directory_iterator(out / "logs"))
    if (entry.is_regular_file())
      EXPECT_FALSE(std::regex_search(test::read_file(entry.path()), secret)) << entry.path();
}

// A stranger replays every genuine message of a launched run byte for byte from its own writers
// (tests/support's rths_rogue, replay): every side drops the replays unread (the MAC covers the
// sending writer's GUID), and launch's summary names each node's count beside its rejects, and
// `rths export` each side's.
TEST(Launch, ReplaysAreDroppedAndCountedPerSideInTheSummaryAndTheExport) {
  runtime::ensure_dds_config();
  const auto dir = test::scratch_dir("launch_replay");
  const auto config = test::write_config(dir, test::paper_frame_study(3, scoped_deployment()));
  const auto out = dir / "out";
  util::ChildProcess rogue(
      test::program("rths_rogue", "tests/support"),
      {"--domain", std::to_string(test::kSharedDomain), "--seconds", "120", "--mode", "replay"},
      dir / "rogue.log");
  std::this_thread::sleep_for(std::chrono::seconds(1));  // discovered before the nodes announce
  const Output o = run(kRths + " launch " + config.string() + " --case lag_shift_14ms " +
                       "--no-plots --bin-dir " + RTHS_BINARY_DIR + " --out " + out.string());
  rogue.terminate();
  ASSERT_EQ(o.code, 0) << o.out << test::read_file(dir / "rogue.log");
  const std::filesystem::path record_path = out / "lag_shift_14ms.rthsrec";
  const auto record = runtime::read_record(record_path);
  ASSERT_NE(record.footer(), nullptr);
  EXPECT_EQ(record.footer()->status(), "completed");
  test::expect_record_equals(record,
                             test::reference_result(test::read_file(config), "lag_shift_14ms"));
  for (const char* node : {"node 1 \\(substructure\\)", "node 2 \\(actuator emulator\\)"})
    EXPECT_TRUE(std::regex_search(
        o.out,
        std::regex(std::string(node) + " DDS messages rejected: [^\n]*unauthenticated [1-9]")))
        << node << "\n"
        << o.out;
  const Output exported =
      run(kRths + " export " + record_path.string() + " --csv " + (dir / "replay.csv").string());
  EXPECT_EQ(exported.code, 0) << exported.out;
  EXPECT_TRUE(std::regex_search(
      exported.out, std::regex(" messages dropped unauthenticated: coordinator [1-9][0-9]*, node 1 "
                               "[1-9][0-9]*, node 2 [1-9]")))
      << exported.out;
  const Output json = run(kRths + " export " + record_path.string() + " --csv " +
                          (dir / "replay_json.csv").string() + " --json");
  ASSERT_EQ(json.code, 0) << json.out;
  const nlohmann::json j = nlohmann::json::parse(json.out);
  EXPECT_GT(j["unauthenticated"].get<std::uint64_t>(), 0u);
  EXPECT_GT(j["node_unauthenticated"]["1"].get<std::uint64_t>(), 0u) << j.dump();
  EXPECT_GT(j["node_unauthenticated"]["2"].get<std::uint64_t>(), 0u) << j.dump();
}

std::vector<std::string> header_of(const std::filesystem::path& csv) {
  std::istringstream line(test::read_file(csv).substr(0, test::read_file(csv).find('\n')));
  std::vector<std::string> cells;
  for (std::string cell; std::getline(line, cell, ',');) cells.push_back(cell);
  return cells;
}

std::size_t rows_of(const std::filesystem::path& csv) {
  const std::string text = test::read_file(csv);
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) - 1;  // - header
}

// `run` and `launch` on one config: the same columns (launch adds the lag per link) and the same
// step count (launch used to report the coordinator's exchange counter: one fewer).
TEST(Launch, WritesRunsColumnsPlusLagPerLinkAndTheSameStepCount) {
  const auto dir = test::scratch_dir("launch_columns");
  const auto config = test::write_config(dir, test::paper_frame_study(0.5, scoped_deployment()));
  const Output ran =
      run(kRths + " run " + config.string() + " --no-plots --json --out " + (dir / "run").string());
  ASSERT_EQ(ran.code, 0) << ran.out;
  const Output launched =
      run(kRths + " launch " + config.string() + " --no-plots --json --bin-dir " + RTHS_BINARY_DIR +
          " --out " + (dir / "launch").string());
  ASSERT_EQ(launched.code, 0) << launched.out;

  const auto run_header = header_of(dir / "run" / "results.csv");
  std::vector<std::string> launch_header, lag_columns;
  for (const auto& cell : header_of(dir / "launch" / "results.csv"))
    (cell.find("_node") == std::string::npos ? launch_header : lag_columns).push_back(cell);
  EXPECT_EQ(launch_header, run_header);
  for (const std::string c : {"reference", "lag_shift_14ms", "jitter"})
    for (const std::string link : {"1", "2"})
      for (const std::string what : {"injected_lag_s", "round_trip_s"})
        EXPECT_EQ(
            std::count(lag_columns.begin(), lag_columns.end(), c + "_node" + link + "_" + what), 1)
            << c << " node " << link << " " << what;

  EXPECT_EQ(rows_of(dir / "launch" / "results.csv"), rows_of(dir / "run" / "results.csv"));
  const auto run_json = nlohmann::json::parse(ran.out);
  const auto launch_json = nlohmann::json::parse(launched.out);
  ASSERT_EQ(launch_json["cases"].size(), run_json["cases"].size());
  for (std::size_t i = 0; i < run_json["cases"].size(); ++i) {
    EXPECT_EQ(launch_json["cases"][i]["steps"], run_json["cases"][i]["steps"]) << i;
    EXPECT_EQ(launch_json["cases"][i]["steps"].get<std::size_t>(),
              rows_of(dir / "launch" / "results.csv"));
  }
}

// A study whose reference case is lagged: `run` compares with that case, but every distributed
// case is compared with the lag-free in-process run, and the summary says so.
TEST(Launch, ComparesEveryCaseWithTheLagFreeInProcessReference) {
  const auto dir = test::scratch_dir("launch_reference");
  const std::string lag_free_named = test::paper_frame_study(0.5, scoped_deployment());
  const auto config =
      test::write_config(dir, "reference_case: \"lag_shift_14ms\"\n" + lag_free_named);
  const Output launched =
      run(kRths + " launch " + config.string() + " --case lag_shift_14ms --no-plots --bin-dir " +
          RTHS_BINARY_DIR + " --out " + (dir / "launch").string());
  ASSERT_EQ(launched.code, 0) << launched.out;
  EXPECT_NE(launched.out.find("against the lag-free in-process reference"), std::string::npos)
      << launched.out;
  const auto summary = nlohmann::json::parse(test::read_file(dir / "launch" / "summary.json"));
  const double launched_nrmse = summary["cases"][0]["nrmse_pct"].get<double>();

  const auto plain = dir / "plain";
  std::filesystem::create_directories(plain);
  const Output ran = run(kRths + " run " + test::write_config(plain, lag_free_named).string() +
                         " --no-plots --json --out " + (plain / "run").string());
  ASSERT_EQ(ran.code, 0) << ran.out;
  const auto run_json = nlohmann::json::parse(ran.out);
  ASSERT_EQ(run_json["cases"][1]["name"], "lag_shift_14ms");
  const double in_process_nrmse = run_json["cases"][1]["nrmse_pct"].get<double>();
  EXPECT_GT(launched_nrmse, 1.0);
  EXPECT_NEAR(launched_nrmse, in_process_nrmse, 1e-9 * in_process_nrmse);
}

// A benchmark study gets J1-J9 after `rths launch` as after `rths run`: the benchmark's case 1 cut
// to 7 s (lockstep), its sample controller's criteria equal to the in-process run's,
// each named, and no published value (the cut motion is not the published one).
TEST(Launch, ComputesTheBenchmarkCriteriaAsRunDoes) {
  const auto dir = test::scratch_dir("launch_benchmark");
  const std::filesystem::path source = std::filesystem::path(RTHS_SOURCE_DIR) / "configs/benchmark";
  for (const char* file : {"case_1.mat", "el_centro.txt"})
    std::filesystem::copy_file(source / file, dir / file,
                               std::filesystem::copy_options::overwrite_existing);
  std::string text = test::read_file(source / "case_1.textproto");
  const std::string scale = "scale: 0.4 }";
  text.replace(text.find(scale), scale.size(), "scale: 0.4 duration: 7 }");
  text += scoped_deployment() + "\n";
  const auto config = test::write_config(dir, text);
  const Output launched = run(kRths + " launch " + config.string() + " --no-plots --bin-dir " +
                              RTHS_BINARY_DIR + " --out " + (dir / "launch").string());
  ASSERT_EQ(launched.code, 0) << launched.out;
  EXPECT_NE(launched.out.find("J5 (%)"), std::string::npos) << launched.out;
  const Output in_process =
      run(kRths + " run " + config.string() + " --no-plots --json --out " + (dir / "run").string());
  ASSERT_EQ(in_process.code, 0) << in_process.out;
  const auto read = [](const std::filesystem::path& file) {
    return nlohmann::json::parse(test::read_file(file));
  };
  const auto distributed = read(dir / "launch" / "benchmark.json");
  const auto local = read(dir / "run" / "benchmark.json");
  ASSERT_EQ(distributed["cases"].size(), 1u);  // the study's reference case is not judged
  EXPECT_EQ(distributed["cases"][0]["name"], "sample_controller");
  EXPECT_EQ(distributed["cases"][0]["criteria"], local["cases"][0]["criteria"]);
  EXPECT_EQ(distributed["cases"][0]["criteria"][3]["name"], "J4");
  EXPECT_TRUE(distributed["cases"][0]["vs_published"].is_null());
}

TEST(Launch, RunIdsHaveOneFormat) {
  char host[128] = {};
  gethostname(host, sizeof host - 1);
  const std::string tail = std::string(host) + "-" + std::to_string(getpid()) + "-";
  const std::string id = runtime::make_run_id("paper frame-lag/14ms");
  EXPECT_EQ(id.rfind("paper_frame-lag_14ms-" + tail, 0), 0u) << id;
  EXPECT_EQ(runtime::make_run_id().rfind(tail, 0), 0u);  // the coordinator's own default format
  EXPECT_NE(runtime::make_run_id("a"), runtime::make_run_id("a"));
}

TEST(Launch, LockstepSharesOneCpuUpToThreeNodesAndSpreadsWithMore) {
  const auto deployment = [](const std::string& text) {
    config::Deployment d;
    EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &d)) << text;
    return d;
  };
  const std::string two =
      "nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR } ";
  const std::string three = two + "nodes { id: 3 kind: SUBSTRUCTURE } ";
  const std::string four = three + "nodes { id: 4 kind: SUBSTRUCTURE } ";
  using runtime::CpuPlacement;
  EXPECT_TRUE(runtime::on_one_cpu(CpuPlacement::kAuto, deployment(two)));
  EXPECT_TRUE(runtime::on_one_cpu(CpuPlacement::kAuto, deployment(three)));
  EXPECT_FALSE(runtime::on_one_cpu(CpuPlacement::kAuto, deployment(four)));
  EXPECT_FALSE(runtime::on_one_cpu(CpuPlacement::kAuto, deployment(two + "clock: REAL_TIME")));
  EXPECT_TRUE(runtime::on_one_cpu(CpuPlacement::kOneCpu, deployment(three + "clock: REAL_TIME")));
  EXPECT_FALSE(runtime::on_one_cpu(CpuPlacement::kSpread, deployment(two)));
}

TEST(Launch, BadDeploymentIsBadInputBeforeAnythingStarts) {
  const auto dir = test::scratch_dir("launch_bad");
  const auto config = test::write_config(
      dir, test::paper_frame_study(1, "deployment { nodes { id: 1 kind: SUBSTRUCTURE } }"));
  const Output o = run(kRths + " launch " + config.string() + " --bin-dir " + RTHS_BINARY_DIR +
                       " --out " + (dir / "out").string());
  EXPECT_EQ(o.code, 2);
}

TEST(Export, WritesOneRowPerStepAndWarnsOnATruncatedRecord) {
  runtime::ensure_dds_config();
  const std::string text = test::paper_frame_study(0.5, "");
  const auto launched =
      test::launch("export", text, "lag_shift_14ms", test::scope_dds_to_this_test());
  ASSERT_EQ(launched.launch.coordinator_exit, 0);
  const auto record = launched.dir / "run.rthsrec";
  const auto csv = launched.dir / "run.csv";
  Output o = run(kRths + " export " + record.string() + " --csv " + csv.string() + " --json");
  ASSERT_EQ(o.code, 0) << o.out;
  const auto steps = static_cast<long>(launched.record.steps().size());
  ASSERT_GT(steps, 100);
  EXPECT_EQ(nlohmann::json::parse(o.out)["rows"].get<long>(), steps);
  const std::string table = test::read_file(csv);
  EXPECT_EQ(table.rfind("step,time_s,ground_acceleration_m_per_s2,u_floor1_m,v_floor1_m_per_s,"
                        "a_floor1_m_per_s2,command_act1_m,measured_act1_m,force_act1_N,",
                        0),
            0u)
      << table.substr(0, 200);
  EXPECT_NE(table.find("node2_round_trip_s"), std::string::npos);
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), steps + 1);  // + header

  std::filesystem::resize_file(record, std::filesystem::file_size(record) - 5);
  o = run(kRths + " export " + record.string() + " --csv " + csv.string() + " --json");
  ASSERT_EQ(o.code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  EXPECT_TRUE(j["truncated"].get<bool>());
  EXPECT_EQ(j["rows"].get<long>(), steps);  // only the footer was cut

  EXPECT_EQ(run(kRths + " export /nonexistent.rthsrec --csv " + csv.string()).code, 2);

  // Cut exactly where the footer began: no entry is cut, and still it reads as truncated.
  const auto& offsets = launched.record.offsets;
  std::filesystem::resize_file(record, offsets.back());
  o = run(kRths + " export " + record.string() + " --csv " + csv.string() + " --json");
  ASSERT_EQ(o.code, 0) << o.out;
  EXPECT_TRUE(nlohmann::json::parse(o.out)["truncated"].get<bool>()) << o.out;
}

// The header is written again before the footer: a flipped byte in the first copy loses no step
// (the export still names the damage and exits 1).
TEST(Export, AFlippedHeaderByteLosesNoStep) {
  runtime::ensure_dds_config();
  const auto launched = test::launch("export_header", test::paper_frame_study(0.5, ""),
                                     "lag_shift_14ms", test::scope_dds_to_this_test());
  ASSERT_EQ(launched.launch.coordinator_exit, 0);
  const auto& entries = launched.record.entries;
  ASSERT_TRUE(entries.front().has_header());
  ASSERT_TRUE(entries[entries.size() - 2].has_header()) << "the header again, before the footer";
  const auto record = launched.dir / "run.rthsrec";
  {
    std::fstream bytes(record, std::ios::in | std::ios::out | std::ios::binary);
    bytes.seekg(static_cast<std::streamoff>(launched.record.offsets.front() + 20));
    const char c = static_cast<char>(bytes.get());
    bytes.seekp(static_cast<std::streamoff>(launched.record.offsets.front() + 20));
    bytes.put(static_cast<char>(c ^ 0x40));
  }
  const auto csv = launched.dir / "run.csv";
  const Output o = run(kRths + " export " + record.string() + " --csv " + csv.string() + " --json");
  EXPECT_EQ(o.code, 1) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  EXPECT_EQ(j["rows"].get<long>(), static_cast<long>(launched.record.steps().size()));
  EXPECT_EQ(j["damaged_regions"].get<long>(), 1);
}

// Records whose checksums hold but whose meaning does not: each problem named with its entry,
// exit 1; a header that cannot size a table writes nothing (never bad_alloc).
TEST(Export, NamesImplausibleEntriesAndExits1) {
  const auto dir = test::scratch_dir("export_implausible");
  const auto write = [&dir](const std::string& name, int schema, int dofs, double u) {
    std::string bytes(runtime::record_preamble());
    runtime::RecordEntry entry;
    entry.mutable_header()->set_schema_version(static_cast<std::uint32_t>(schema));
    entry.mutable_header()->set_dofs(dofs);
    runtime::append_record_frame(entry, bytes);
    for (int k : {0, 1, 1}) {
      entry.Clear();
      entry.mutable_step()->set_step(k);
      entry.mutable_step()->add_displacement(k == 1 ? u : 0.0);
      runtime::append_record_frame(entry, bytes);
    }
    entry.Clear();
    entry.mutable_footer()->set_status("completed");
    runtime::append_record_frame(entry, bytes);
    std::ofstream(dir / name, std::ios::binary) << bytes;
    return dir / name;
  };
  const auto csv = (dir / "out.csv").string();
  const Output nonsense =
      run(kRths + " export " + write("nonsense.rthsrec", 999, 1, std::nan("")).string() +
          " --csv " + csv + " --json");
  EXPECT_EQ(nonsense.code, 1) << nonsense.out;
  const auto j = nlohmann::json::parse(nonsense.out);
  const std::string problems = j["problems"].dump();
  EXPECT_NE(problems.find("entry 0 (header): schema version 999"), std::string::npos) << problems;
  // Entries 2 and 3 (both step 1) carry the same non-finite value: one region, named once.
  EXPECT_NE(problems.find("entries 2-3 (steps 1-1, 2 steps): displacement[0] is not finite"),
            std::string::npos)
      << problems;
  EXPECT_NE(problems.find("entry 3 (step 1): comes after step 1 (a duplicate)"), std::string::npos)
      << problems;
  for (int dofs : {-1, 100000}) {
    std::filesystem::remove(csv);
    const Output huge =
        run(kRths + " export " + write("dofs.rthsrec", runtime::kSchemaVersion, dofs, 0).string() +
            " --csv " + csv);
    EXPECT_EQ(huge.code, 1) << dofs;
    EXPECT_FALSE(std::filesystem::exists(csv)) << dofs;
  }
}

}  // namespace
}  // namespace rths
