// `rths launch` and `rths export` end to end (the real binary; domains 17-18).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>

#include "test_support.h"

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

TEST(Launch, RunsEveryCaseAndWritesRecordsCsvAndASummary) {
  const auto dir = test::scratch_dir("launch_cli");
  const auto config = test::write_config(
      dir, test::paper_frame_study(1.5, "deployment { domain_id: 17 }"));
  const auto out = dir / "out";
  const Output o = run(kRths + " launch " + config.string() + " --case reference --case " +
                       "lag_shift_14ms --no-plots --json --bin-dir " + RTHS_BINARY_DIR +
                       " --out " + out.string());
  ASSERT_EQ(o.code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_EQ(j["cases"].size(), 2u);
  EXPECT_EQ(j["cases"][0]["status"], "completed");
  EXPECT_TRUE(j["cases"][0]["nrmse_vs_reference"].is_null());
  EXPECT_GT(j["cases"][1]["nrmse_vs_reference"].get<double>(), 0.0);
  EXPECT_GT(j["cases"][1]["links"]["2"]["round_trip_median"].get<double>(), 0.0);
  // launch itself checks the lockstep runs against the in-process simulation.
  EXPECT_EQ(j["cases"][0]["max_difference_from_in_process_m"].get<double>(), 0.0);
  EXPECT_EQ(j["cases"][1]["max_difference_from_in_process_m"].get<double>(), 0.0);
  const auto record = runtime::read_record(out / "lag_shift_14ms.rthsrec");
  test::expect_record_equals(record, test::reference_result(test::read_file(config), "lag_shift_14ms"));
  EXPECT_TRUE(std::filesystem::exists(out / "reference.csv"));
  EXPECT_TRUE(std::filesystem::exists(out / "logs" / "reference" / "coordinator.log"));
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
  const auto launched = test::launch("export", text, "lag_shift_14ms", 18);
  ASSERT_EQ(launched.launch.coordinator_exit, 0);
  const auto record = launched.dir / "run.rthsrec";
  const auto csv = launched.dir / "run.csv";
  Output o = run(kRths + " export " + record.string() + " --csv " + csv.string() + " --json");
  ASSERT_EQ(o.code, 0) << o.out;
  const auto steps = static_cast<long>(launched.record.steps().size());
  ASSERT_GT(steps, 100);
  EXPECT_EQ(nlohmann::json::parse(o.out)["rows"].get<long>(), steps);
  const std::string table = test::read_file(csv);
  EXPECT_EQ(table.rfind("step,time,ground_acceleration,u1,v1,a1,command1,realised1,force1,", 0), 0u)
      << table.substr(0, 200);
  EXPECT_NE(table.find("node2_round_trip"), std::string::npos);
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), steps + 1);  // + header

  std::filesystem::resize_file(record, std::filesystem::file_size(record) - 5);
  o = run(kRths + " export " + record.string() + " --csv " + csv.string() + " --json");
  ASSERT_EQ(o.code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  EXPECT_TRUE(j["truncated"].get<bool>());
  EXPECT_EQ(j["rows"].get<long>(), steps);  // only the footer was cut

  EXPECT_EQ(run(kRths + " export /nonexistent.rthsrec --csv " + csv.string()).code, 2);
}

}  // namespace
}  // namespace rths
