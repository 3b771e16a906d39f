// The sweep grid: its order, its shards, and the configs it refuses.
#include "analysis/sweep/sweep_grid.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "study/study.h"
#include "sweep_study.h"

namespace rths::analysis {
namespace {

using sweep_test::grid_for;
using sweep_test::kMotionDir;
using sweep_test::study_text;

TEST(SweepGrid, OrderHasDelayInnermost) {
  const SweepGrid grid = grid_for(
      "periods: [0.5, 1.0, 2.0] delays: [0.002, 0.01] "
      "experimental_fractions: [0.5, 1.0] stiffnesses: [100, 200]");
  EXPECT_EQ(grid.size(), 3u * 2 * 2 * 2);
  const SweepPoint p = grid.point(1 + 2 * 1 + 4 * 2 + 12 * 1);
  EXPECT_EQ(p.delay, 0.01);
  EXPECT_EQ(p.alpha, 1.0);
  EXPECT_EQ(p.period, 2.0);
  EXPECT_EQ(p.stiffness, 200);
  EXPECT_DOUBLE_EQ(p.dt, 0.002);
}

TEST(SweepGrid, ShardsCoverTheGridOnce) {
  const SweepGrid grid = grid_for(
      "periods: [0.3, 0.8, 1.6] delays: [0.002, 0.004, 0.006, 0.008] "
      "experimental_fractions: [0.5]");
  std::size_t next = 0;
  for (std::size_t i = 0; i < 5; ++i) {
    const auto [first, last] = grid.shard_range({i, 5});
    EXPECT_EQ(first, next);
    next = last;
  }
  EXPECT_EQ(next, grid.size());
}

TEST(SweepShard, ParsesAndRejects) {
  const Shard shard = parse_shard("2/7");
  EXPECT_EQ(shard.index, 2u);
  EXPECT_EQ(shard.count, 7u);
  EXPECT_EQ(shard.to_string(), "2/7");
  for (const char* bad : {"7/7", "1", "a/3", "1/0", "-1/3", "1/3x"}) {
    EXPECT_THROW(parse_shard(bad), std::invalid_argument) << bad;
  }
}

void expect_bad_config(const std::string& text, const std::string& expected_fragment) {
  try {
    const config::Study study = study::parse_study(text, "bad.textproto");
    SweepGrid grid(study, kMotionDir, "bad.textproto");
    ADD_FAILURE() << "accepted a config that should fail with '" << expected_fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(expected_fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.textproto"), std::string::npos) << e.what();
  }
}

TEST(SweepGrid, BadInputNamesTheField) {
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] delay_model: LAG"),
                    "delay_model");  // refused by the parser: an enum
  expect_bad_config(study_text("periods: [0.5]"), "sweep.delays");
  expect_bad_config(study_text("periods: [-0.5] delays: [0.01]"), "sweep.periods");
  expect_bad_config(study_text("periods: [0.5] delays: [-0.01]"), "sweep.delays");
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] experimental_fractions: [1.5]"),
                    "experimental_fractions");
  expect_bad_config(study_text("periods: [0.5] delays: [0.01] pariods: [1]"), "pariods");
  expect_bad_config(
      study_text("periods: [0.5] delays: [0.01] models { bilinear { yield_displacement: 0 } }"),
      "sweep.models[0]");
  // omega dt = 2 pi / 0.003 * 0.002 > 2: beyond explicit Newmark's limit.
  expect_bad_config(study_text("periods: [0.003, 0.5] delays: [0.01]"), "shortest period");
  expect_bad_config(R"(structure { shear_building { storey_mass: [1, 1] storey_stiffness: [1, 1] } }
                       sweep { periods: [0.5] delays: [0.01] motions { path: "RSN175_IMPVALL.H_H-E12140.AT2" } })",
                    "structure.sdof");
  expect_bad_config(
      study_text("periods: [0.5] delays: [0.01] motions { path: \"no_such_record.AT2\" }"),
      "no_such_record");
}

}  // namespace
}  // namespace rths::analysis
