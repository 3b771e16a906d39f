// The sweep: the paper's Fig. 4 trends on a small grid, the fast (batch kernel) path against the
// general one, shards and their merge, and bad configs.
#include "analysis/sweep.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "core/study.h"

namespace rths::analysis {
namespace {

namespace fs = std::filesystem;

const fs::path kMotionDir = fs::path(RTHS_SHARED_DATA_DIR) / "ground_motions";
// Round-off between the two paths and across stiffnesses, relative to the error itself.
constexpr double kRoundOff = 1e-9;

// A small grid under the 1979 Imperial Valley record, first 12 s, dt = 2 ms.
std::string study_text(const std::string& sweep_body, const std::string& integrator = "") {
  return R"(
name: "sweep_test"
structure { sdof { period: 0.5 } damping { modal_zeta: 0.05 } }
integrator { kind: EXPLICIT_NEWMARK )" + integrator + R"( }
sweep {
  motions { path: "RSN175_IMPVALL.H_H-E12140.AT2" duration: 12 }
  dts: 0.002
)" + sweep_body + "}\n";
}

SweepGrid grid_for(const std::string& sweep_body, const std::string& integrator = "") {
  return SweepGrid(core::parse_study(study_text(sweep_body, integrator), "test.textproto"),
                   kMotionDir, "test.textproto");
}

std::vector<SweepTableRow> run_table(const SweepGrid& grid, bool general_only = false) {
  SweepOptions options;
  options.general_path_only = general_only;
  options.threads = 2;
  return to_table(grid, run_sweep(grid, options));
}

double relative_difference(double a, double b) {
  const double scale = std::max(std::abs(a), std::abs(b));
  return scale == 0 ? 0.0 : std::abs(a - b) / scale;
}

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rths_sweep_test_" + name + "_" + std::to_string(::getpid()));
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

TEST(Sweep, GridOrderHasDelayInnermost) {
  const SweepGrid grid = grid_for("periods: [0.5, 1.0, 2.0] delays: [0.002, 0.01] "
                                  "experimental_fractions: [0.5, 1.0] stiffnesses: [100, 200]");
  EXPECT_EQ(grid.size(), 3u * 2 * 2 * 2);
  const SweepPoint p = grid.point(1 + 2 * 1 + 4 * 2 + 12 * 1);
  EXPECT_EQ(p.delay, 0.01);
  EXPECT_EQ(p.alpha, 1.0);
  EXPECT_EQ(p.period, 2.0);
  EXPECT_EQ(p.stiffness, 200);
  EXPECT_DOUBLE_EQ(p.dt, 0.002);
}

TEST(Sweep, BatchKernelPathAgreesWithGeneralPath) {
  const SweepGrid grid = grid_for("periods: [0.3, 0.7, 1.5, 3.0] delays: [0, 0.004, 0.0105] "
                                  "experimental_fractions: [0.4, 1.0]");
  const auto fast = run_table(grid, false);
  const auto general = run_table(grid, true);
  ASSERT_EQ(fast.size(), general.size());
  std::size_t compared = 0;
  for (std::size_t i = 0; i < fast.size(); ++i) {
    ASSERT_EQ(fast[i].index, general[i].index);
    EXPECT_EQ(fast[i].diverged, general[i].diverged) << "point " << i;
    if (fast[i].diverged) continue;
    EXPECT_LT(relative_difference(fast[i].peak_reference, general[i].peak_reference), kRoundOff);
    EXPECT_LT(relative_difference(fast[i].peak_delayed, general[i].peak_delayed), kRoundOff);
    if (fast[i].delay > 0) {
      EXPECT_LT(relative_difference(fast[i].nrmse_pct, general[i].nrmse_pct), kRoundOff) << "point " << i;
      EXPECT_LT(relative_difference(fast[i].eq2_paper, general[i].eq2_paper), kRoundOff);
      ++compared;
    }
  }
  EXPECT_GT(compared, fast.size() / 2);
}

TEST(Sweep, StiffnessHasNoInfluenceAtAFixedPeriod) {
  for (bool general_only : {true, false}) {
    const SweepGrid grid = grid_for("periods: [0.4, 1.2] delays: [0.003, 0.008] "
                                    "experimental_fractions: [0.5] stiffnesses: [1e3, 2.5e5, 7e7]");
    const auto rows = run_table(grid, general_only);
    std::size_t checked = 0;
    for (const auto& r : rows) {
      if (r.stiffness == 1e3) continue;
      const auto same = std::find_if(rows.begin(), rows.end(), [&](const SweepTableRow& o) {
        return o.stiffness == 1e3 && o.period == r.period && o.delay == r.delay;
      });
      ASSERT_NE(same, rows.end());
      ASSERT_FALSE(r.diverged);
      EXPECT_GT(r.nrmse_pct, 1e-3);  // a real error, not round-off, is being compared
      EXPECT_LT(relative_difference(r.nrmse_pct, same->nrmse_pct), kRoundOff) << "T " << r.period;
      EXPECT_LT(relative_difference(r.peak_error, same->peak_error), kRoundOff);
      ++checked;
    }
    EXPECT_EQ(checked, 8u);
    EXPECT_LT(measure_trends(rows).stiffness_max_relative_difference, kRoundOff);
  }
}

TEST(Sweep, ErrorFallsWithPeriod) {
  const SweepGrid grid = grid_for("periods: [0.25, 0.5, 1.0, 2.0, 3.0] delays: [0.004, 0.01] "
                                  "experimental_fractions: [0.33]");
  const auto rows = run_table(grid);
  for (double delay : {0.004, 0.01}) {
    std::vector<double> errors;
    for (const auto& r : rows) {
      if (r.delay == delay) {
        ASSERT_FALSE(r.diverged);
        errors.push_back(r.nrmse_pct);
      }
    }
    ASSERT_EQ(errors.size(), 5u);
    for (std::size_t i = 1; i < errors.size(); ++i) {
      EXPECT_LT(errors[i], errors[i - 1]) << "delay " << delay << " period index " << i;
    }
    EXPECT_GT(errors.front(), 5 * errors.back());
  }
  EXPECT_EQ(measure_trends(rows).period_falling_fraction, 1.0);
}

TEST(Sweep, SofteningResponseHasSmallerDelayErrorThanLinear) {
  // uy = 3 mm: the linear system at these periods peaks at several times that.
  const SweepGrid grid = grid_for(
      "periods: [0.4, 0.6, 1.0] delays: [0.006] experimental_fractions: [0.33] "
      "models { linear {} } models { bilinear { yield_displacement: 0.003 post_yield_ratio: 0.1 } }");
  const auto rows = run_table(grid);
  std::size_t compared = 0;
  for (const auto& linear : rows) {
    if (linear.model != "linear") continue;
    const auto bilinear = std::find_if(rows.begin(), rows.end(), [&](const SweepTableRow& o) {
      return o.model != "linear" && o.period == linear.period;
    });
    ASSERT_NE(bilinear, rows.end());
    ASSERT_FALSE(linear.diverged || bilinear->diverged);
    EXPECT_GT(linear.peak_reference, 3 * 0.003) << "must yield substantially, T " << linear.period;
    EXPECT_LT(bilinear->nrmse_pct, linear.nrmse_pct) << "T " << linear.period;
    ++compared;
  }
  EXPECT_EQ(compared, 3u);
  EXPECT_LT(measure_trends(rows).nonlinear_to_linear_median_ratio, 1.0);
}

class SweepShards : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs shard i/N of the grid and writes its CSV.
  fs::path run_shard(const SweepGrid& grid, std::size_t index, std::size_t count, const std::string& tag = "") {
    SweepOptions options;
    options.shard = {index, count};
    options.threads = 2;
    const fs::path path = dir_ / (tag + "shard" + std::to_string(index) + "of" + std::to_string(count) + ".csv");
    write_sweep_csv(path, grid, options.shard, run_sweep(grid, options));
    return path;
  }

  static constexpr const char* kBody =
      "periods: [0.3, 0.8, 1.6, 2.5] delays: [0.002, 0.0075] experimental_fractions: [0.5, 1.0] "
      "models { linear {} } models { bilinear { yield_displacement: 0.01 post_yield_ratio: 0.2 } }";
  fs::path dir_;
};

TEST_F(SweepShards, MergedShardsEqualTheUnshardedRunByteForByte) {
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

TEST_F(SweepShards, MergeRefusesAMissingShard) {
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

TEST_F(SweepShards, MergeRefusesADuplicatedShard) {
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

TEST_F(SweepShards, MergeRefusesAShardOfAnotherGrid) {
  const SweepGrid grid = grid_for(kBody);
  // Same size and shape, one delay differs: only the grid hash tells them apart.
  const SweepGrid other = grid_for(
      "periods: [0.3, 0.8, 1.6, 2.5] delays: [0.002, 0.0076] experimental_fractions: [0.5, 1.0] "
      "models { linear {} } models { bilinear { yield_displacement: 0.01 post_yield_ratio: 0.2 } }");
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

TEST_F(SweepShards, ReadingRefusesATruncatedCsv) {
  const SweepGrid grid = grid_for(kBody);
  const fs::path a = run_shard(grid, 0, 2);
  std::string text = slurp(a);
  text.resize(text.size() - 30);  // cut inside the last row
  std::ofstream(dir_ / "cut.csv", std::ios::binary) << text;
  EXPECT_THROW(read_sweep_csv(dir_ / "cut.csv"), std::invalid_argument);
  std::ofstream(dir_ / "other.csv") << "time,u\n0,0\n";
  EXPECT_THROW(read_sweep_csv(dir_ / "other.csv"), std::invalid_argument);
}

TEST_F(SweepShards, CsvIsPlainWithUnitsAndItsMetadataIsInASidecar) {
  const SweepGrid grid = grid_for(kBody);
  const fs::path a = run_shard(grid, 1, 2);
  std::ifstream in(a);
  std::string header;
  std::getline(in, header);
  // A naive CSV reader sees the column names first: no comment line, units in the names.
  EXPECT_EQ(header.rfind("index,period_s,delay_s,", 0), 0u) << header;
  EXPECT_NE(header.find(",nrmse_pct,"), std::string::npos) << header;
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

TEST(SweepShard, ParsesAndRejects) {
  const Shard shard = parse_shard("2/7");
  EXPECT_EQ(shard.index, 2u);
  EXPECT_EQ(shard.count, 7u);
  for (const char* bad : {"7/7", "1", "a/3", "1/0", "-1/3", "1/3x"}) {
    EXPECT_THROW(parse_shard(bad), std::invalid_argument) << bad;
  }
}

TEST(SweepShard, SlicesCoverTheGridOnce) {
  const SweepGrid grid = grid_for("periods: [0.3, 0.8, 1.6] delays: [0.002, 0.004, 0.006, 0.008] "
                                  "experimental_fractions: [0.5]");
  std::size_t next = 0;
  for (std::size_t i = 0; i < 5; ++i) {
    const auto [first, last] = grid.shard_range({i, 5});
    EXPECT_EQ(first, next);
    next = last;
  }
  EXPECT_EQ(next, grid.size());
}

void expect_bad_config(const std::string& text, const std::string& expected_fragment) {
  try {
    const config::Study study = core::parse_study(text, "bad.textproto");
    SweepGrid grid(study, kMotionDir, "bad.textproto");
    ADD_FAILURE() << "accepted a config that should fail with '" << expected_fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(expected_fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.textproto"), std::string::npos) << e.what();
  }
}

TEST(SweepConfig, BadInputNamesTheField) {
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] delay_model: LAG"), "delay_model");  // refused by the parser: an enum
  expect_bad_config(study_text("periods: [0.5]"), "sweep.delays");
  expect_bad_config(study_text("periods: [-0.5] delays: [0.01]"), "sweep.periods");
  expect_bad_config(study_text("periods: [0.5] delays: [-0.01]"), "sweep.delays");
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] experimental_fractions: [1.5]"),
                    "experimental_fractions");
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] pariods: [1]"), "pariods");
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] models { bilinear { yield_displacement: 0 } }"),
                    "sweep.models[0]");
  // omega dt = 2 pi / 0.003 * 0.002 > 2: beyond explicit Newmark's limit.
  expect_bad_config(study_text("periods: [0.003, 0.5] delays: [0.01]"), "shortest period");
  expect_bad_config(R"(structure { shear_building { storey_mass: [1, 1] storey_stiffness: [1, 1] } }
                       sweep { periods: [0.5] delays: [0.01] motions { path: "RSN175_IMPVALL.H_H-E12140.AT2" } })",
                    "structure.sdof");
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] motions { path: \"no_such_record.AT2\" }"),
                    "no_such_record");
}

}  // namespace
}  // namespace rths::analysis
