// Sweep CSVs: shards written, read back and merged; what the file holds and its sidecar.
#include "analysis/sweep/sweep_csv.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "sweep_study.h"

namespace rths::analysis {
namespace {

namespace fs = std::filesystem;
using sweep_test::grid_for;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("rths_sweep_csv_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class SweepCsvFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs shard i/N of the grid and writes its CSV.
  fs::path run_shard(const SweepGrid& grid, std::size_t index, std::size_t count,
                     const std::string& tag = "") {
    SweepOptions options;
    options.shard = {index, count};
    options.threads = 2;
    const fs::path path =
        dir_ / (tag + "shard" + std::to_string(index) + "of" + std::to_string(count) + ".csv");
    write_sweep_csv(path, grid, options.shard, run_sweep(grid, options));
    return path;
  }

  static constexpr const char* kBody =
      "periods: [0.3, 0.8, 1.6, 2.5] delays: [0.002, 0.0075] experimental_fractions: [0.5, 1.0] "
      "models { linear {} } models { bilinear { yield_displacement: 0.01 post_yield_ratio: 0.2 } }";
  fs::path dir_;
};

TEST_F(SweepCsvFiles, MergedShardsEqualTheUnshardedRunByteForByte) {
  const SweepGrid grid = grid_for(kBody);
  const fs::path whole = run_shard(grid, 0, 1);
  // 5 shards over 32 points: uneven slices that cut a period block and a model group.
  std::vector<fs::path> shards;
  for (std::size_t i = 0; i < 5; ++i) shards.push_back(run_shard(grid, i, 5));
  std::reverse(shards.begin(), shards.end());  // order of the arguments must not matter
  const SweepCsv merged = merge_sweep_csvs(shards, dir_ / "merged.csv");
  EXPECT_EQ(merged.points, grid.size());
  EXPECT_EQ(slurp(dir_ / "merged.csv"), slurp(whole));
  EXPECT_FALSE(fs::exists(dir_ / "merged.csv.partial"));
}

TEST_F(SweepCsvFiles, MergeRefusesAMissingShard) {
  const SweepGrid grid = grid_for(kBody);
  const std::vector<fs::path> shards = {run_shard(grid, 0, 3), run_shard(grid, 2, 3)};
  try {
    merge_sweep_csvs(shards, dir_ / "merged.csv");
    FAIL() << "merge accepted a gap";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1/3"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "merged.csv"));
}

TEST_F(SweepCsvFiles, MergeRefusesADuplicatedShard) {
  const SweepGrid grid = grid_for(kBody);
  const fs::path a = run_shard(grid, 0, 2), b = run_shard(grid, 1, 2);
  try {
    merge_sweep_csvs({a, b, a}, dir_ / "merged.csv");
    FAIL() << "merge accepted a duplicate";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("twice"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "merged.csv"));
}

TEST_F(SweepCsvFiles, MergeRefusesAShardOfAnotherGrid) {
  const SweepGrid grid = grid_for(kBody);
  // Same size and shape, one delay differs: only the grid hash tells them apart.
  const SweepGrid other = grid_for(
      "periods: [0.3, 0.8, 1.6, 2.5] delays: [0.002, 0.0076] experimental_fractions: [0.5, 1.0] "
      "models { linear {} } models { bilinear { yield_displacement: 0.01 post_yield_ratio: 0.2 } "
      "}");
  ASSERT_EQ(grid.size(), other.size());
  ASSERT_NE(grid.hash(), other.hash());
  const fs::path a = run_shard(grid, 0, 2), b = run_shard(other, 1, 2, "other_");
  try {
    merge_sweep_csvs({a, b}, dir_ / "merged.csv");
    FAIL() << "merge accepted a foreign shard";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("another grid"), std::string::npos) << e.what();
  }
}

TEST_F(SweepCsvFiles, ReadingRefusesATruncatedCsv) {
  const SweepGrid grid = grid_for(kBody);
  const fs::path a = run_shard(grid, 0, 2);
  std::string text = slurp(a);
  text.resize(text.size() - 30);  // cut inside the last row
  std::ofstream(dir_ / "cut.csv", std::ios::binary) << text;
  EXPECT_THROW(read_sweep_csv(dir_ / "cut.csv"), std::invalid_argument);
  std::ofstream(dir_ / "other.csv") << "time,u\n0,0\n";
  EXPECT_THROW(read_sweep_csv(dir_ / "other.csv"), std::invalid_argument);
  // A shard an earlier rths wrote (NRMSE only) is named as such, not read as a broken file.
  fs::copy_file(sweep_sidecar_path(a), sweep_sidecar_path(dir_ / "old.csv"));
  std::ofstream(dir_ / "old.csv")
      << "index,period_s,delay_s,alpha,stiffness_N_per_m,dt_s,motion,model,peak_ref_m,"
         "peak_delayed_m,eq2_paper,nrmse_pct,peak_error_m,diverged\n";
  try {
    read_sweep_csv(dir_ / "old.csv");
    FAIL() << "read a sweep CSV of the earlier format";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("an earlier rths (NRMSE only"), std::string::npos)
        << e.what();
  }
}

TEST_F(SweepCsvFiles, CsvIsPlainWithUnitsAndItsMetadataIsInASidecar) {
  const SweepGrid grid = grid_for(kBody);
  const fs::path a = run_shard(grid, 1, 2);
  std::ifstream in(a);
  std::string header;
  std::getline(in, header);
  // A naive CSV reader sees the column names first: no comment line, units in the names.
  EXPECT_EQ(header.rfind("index,period_s,delay_s,", 0), 0u) << header;
  // E_peak and E_rms lead the errors; the paper's NRMSE and Eq. 2 follow.
  EXPECT_NE(header.find(",peak_error_pct,rms_error_pct,peak_error_m,nrmse_pct,eq2_paper,"),
            std::string::npos)
      << header;
  EXPECT_NE(header.find(",peak_delayed_m,"), std::string::npos) << header;
  const nlohmann::json meta = nlohmann::json::parse(slurp(sweep_sidecar_path(a)));
  EXPECT_EQ(meta["shard"], "1/2");
  EXPECT_EQ(meta["points"], grid.size());
  EXPECT_EQ(meta["grid"], grid.hash_hex());
  fs::remove(sweep_sidecar_path(a));
  try {
    read_sweep_csv(a);
    FAIL() << "read a sweep CSV without its metadata";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("meta.json"), std::string::npos) << e.what();
  }
}

TEST_F(SweepCsvFiles, RowsReadBackEqualTheRowsWritten) {
  const SweepGrid grid = grid_for(kBody);
  SweepOptions options;
  options.threads = 2;
  const std::vector<SweepRow> rows = run_sweep(grid, options);
  const fs::path path = dir_ / "sweep.csv";
  write_sweep_csv(path, grid, options.shard, rows);
  const std::vector<SweepTableRow> written = to_table(grid, rows);
  const std::vector<SweepTableRow> read = parse_sweep_rows(read_sweep_csv(path), path.string());
  ASSERT_EQ(read.size(), written.size());
  for (std::size_t i = 0; i < read.size(); ++i) {
    // 17 significant digits: every double comes back bit for bit.
    EXPECT_EQ(read[i].index, written[i].index);
    EXPECT_EQ(read[i].period, written[i].period);
    EXPECT_EQ(read[i].delay, written[i].delay);
    EXPECT_EQ(read[i].alpha, written[i].alpha);
    EXPECT_EQ(read[i].dt, written[i].dt);
    EXPECT_EQ(read[i].motion, written[i].motion);
    EXPECT_EQ(read[i].model, written[i].model);
    EXPECT_EQ(read[i].peak_error_pct, written[i].peak_error_pct);
    EXPECT_EQ(read[i].rms_error_pct, written[i].rms_error_pct);
    EXPECT_EQ(read[i].nrmse_pct, written[i].nrmse_pct);
    EXPECT_EQ(read[i].eq2_paper, written[i].eq2_paper);
    EXPECT_EQ(read[i].peak_error, written[i].peak_error);
    EXPECT_EQ(read[i].diverged, written[i].diverged);
  }
  SweepCsv bad = read_sweep_csv(path);
  bad.lines.front().replace(bad.lines.front().find(','), 1, ",x");
  EXPECT_THROW(parse_sweep_rows(bad, "bad.csv"), std::invalid_argument);
}

}  // namespace
}  // namespace rths::analysis
