// results::Table: names, lengths, attributes, NaN padding.
#include "results/table.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rths::results {
namespace {

TEST(TableTest, IdentifierMakesAValidMatlabName) {
  EXPECT_EQ(identifier("u_lag 14-ms"), "u_lag_14_ms");
  EXPECT_EQ(identifier("14ms"), "x14ms");
  EXPECT_EQ(identifier(""), "x");
  EXPECT_EQ(identifier(std::string(100, 'a')).size(), 63u);
  EXPECT_TRUE(is_identifier(identifier("_private")));
  EXPECT_FALSE(is_identifier("_private"));
  EXPECT_FALSE(is_identifier("a-b"));
  EXPECT_TRUE(is_identifier("node2_round_trip"));
}

TEST(TableTest, RejectsBadNamesDuplicatesAndUnequalLengths) {
  Table t;
  t.add_numbers("time_s", "s", {0, 1, 2});
  EXPECT_THROW(t.add_numbers("2x_m", "m", {0, 1, 2}), std::invalid_argument);
  EXPECT_THROW(t.add_numbers("time_s", "s", {0, 1, 2}), std::invalid_argument);
  try {
    t.add_texts("name", "", {"a", "b"});
    FAIL() << "a short column was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'name' has 2 rows"), std::string::npos) << e.what();
  }
  t.add_texts("label", "", {"a", "b", "c"});
  EXPECT_EQ(t.rows(), 3u);
  EXPECT_EQ(t.column("label").texts[2], "c");
  EXPECT_EQ(t.column("time_s").unit, "s");
  EXPECT_THROW(t.column("missing"), std::out_of_range);
}

// One naming rule for every writer: a column's name ends in its unit.
TEST(TableTest, EveryNameEndsInItsUnit) {
  Table t;
  t.add_numbers("lag_shift_14ms_u_floor1_m", "m", {0});
  t.add_numbers("a_floor1_m_per_s2", "m/s^2", {0});
  t.add_numbers("nrmse_pct", "%", {0});
  t.add_numbers("step", "", {0});
  EXPECT_EQ(unit_suffix("N/m"), "N_per_m");
  try {
    t.add_numbers("time", "s", {0});
    FAIL() << "a name without its unit was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("must end in '_s'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(t.add_numbers("u_floor1_mm", "m", {0}), std::invalid_argument);
  EXPECT_THROW(t.add_numbers("_m", "m", {0}), std::invalid_argument);
}

// A key names one attribute: text or number, whichever was set last.
TEST(TableTest, AnAttributeIsTextOrANumberNeverBoth) {
  Table t;
  t.set_attribute("dt_s", "0.001");
  t.set_number_attribute("dt_s", 0.001);
  EXPECT_EQ(t.attributes().count("dt_s"), 0u);
  EXPECT_DOUBLE_EQ(t.number_attributes().at("dt_s"), 0.001);
  t.set_attribute("dt_s", "one millisecond");
  EXPECT_EQ(t.number_attributes().count("dt_s"), 0u);
  EXPECT_EQ(t.attributes().at("dt_s"), "one millisecond");
}

TEST(TableTest, PadWithNanFillsShortColumns) {
  std::vector<double> a{1, 2, 3}, b{4};
  pad_with_nan({&a, &b});
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b[0], 4);
  EXPECT_TRUE(std::isnan(b[1]) && std::isnan(b[2]));
}

}  // namespace
}  // namespace rths::results
