// The summary table: columns as wide as their widest cell, numbers right and words left, and a
// cell too long for its column written as a note below instead of pushing the columns apart.
#include "util/text_table.h"

#include <gtest/gtest.h>

#include <sstream>
#include <stdexcept>

namespace rths::util {
namespace {

using Align = TextTable::Align;

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(TextTable, ColumnsLineUpWhateverTheCellWidths) {
  TextTable table({{"case", Align::kLeft}, {"peak (mm)", Align::kRight}});
  table.add_row({"reference", "13.627"});
  table.add_row({"lag", "8.4"});
  const auto out = lines(table.render());
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0], "case       peak (mm)");
  EXPECT_EQ(out[1], "reference     13.627");
  EXPECT_EQ(out[2], "lag              8.4");
}

TEST(TextTable, ACellLongerThanItsColumnBecomesANoteBelow) {
  TextTable table({{"case", Align::kLeft, 10}, {"status", Align::kLeft}});
  table.add_row({"model_based_lag_plus_30pct", "completed"});
  table.add_row({"ats", "completed"});
  const auto out = lines(table.render());
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out[1], "[1]   completed");
  EXPECT_EQ(out[2], "ats   completed");
  EXPECT_EQ(out[3], "[1] model_based_lag_plus_30pct");
}

TEST(TextTable, ARowOfTheWrongSizeIsRefused) {
  TextTable table({{"a"}, {"b"}});
  EXPECT_THROW(table.add_row({"only one"}), std::invalid_argument);
}

}  // namespace
}  // namespace rths::util
