// The one reader of plain-text numeric columns (ground-motion columns and delay traces use it).
#include "study/text_columns.h"

#include <gtest/gtest.h>

#include <fstream>

namespace rths::study {
namespace {

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path) << text;
  return path;
}

std::string error_of(const std::string& text, bool title_allowed) {
  const auto path = write("rths_text_columns_bad.txt", text);
  try {
    read_text_columns(path, "test file", title_allowed);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

TEST(TextColumns, SpacesTabsCommasCommentsAndCrlfAreOneFormat) {
  const auto path = write("rths_text_columns.txt",
                          "# recorded 2026\r\n\r\n0, 1e-3\t# first\r\n0.5  -.25\r\n1,2\r\n");
  const TextColumns t = read_text_columns(path, "test file");
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_TRUE(t.title.empty());
  EXPECT_EQ(t.rows[0].line, 3);
  EXPECT_EQ(t.rows[0].values, (std::vector<double>{0.0, 1e-3}));
  EXPECT_EQ(t.rows[1].values, (std::vector<double>{0.5, -0.25}));
  EXPECT_EQ(t.rows[2].line, 5);
  EXPECT_EQ(t.rows[2].values, (std::vector<double>{1.0, 2.0}));
}

// The streaming form visits the rows read_text_columns keeps, with their lines, and the title;
// an error stops it at the bad line as it stops the whole read.
TEST(TextColumns, EachRowIsVisitedAsTheWholeReadKeepsIt) {
  const auto path = write("rths_text_columns_visit.txt", "time,accel\n# c\n0 1\n\n0.5 -2 # x\n");
  const TextColumns whole = read_text_columns(path, "test file", true);
  std::vector<TextRow> visited;
  std::vector<std::string> title;
  for_each_text_row(
      path, "test file", true,
      [&](int line, const std::vector<double>& values) {
        visited.push_back({line, values});
      },
      &title);
  ASSERT_EQ(visited.size(), whole.rows.size());
  for (std::size_t i = 0; i < visited.size(); ++i) {
    EXPECT_EQ(visited[i].line, whole.rows[i].line);
    EXPECT_EQ(visited[i].values, whole.rows[i].values);
  }
  EXPECT_EQ(visited.back().line, 5);
  EXPECT_EQ(title, (std::vector<std::string>{"time", "accel"}));
  const auto bad = write("rths_text_columns_visit_bad.txt", "1\n2\nx\n4\n");
  int seen = 0;
  EXPECT_THROW(
      for_each_text_row(bad, "test file", false, [&](int, const std::vector<double>&) { ++seen; }),
      std::invalid_argument);
  EXPECT_EQ(seen, 2);
}

TEST(TextColumns, ATitleLineOnlyWhereAllowedAndOnlyFirst) {
  const auto path = write("rths_text_columns_title.txt", "time,accel\n0 1\n");
  const TextColumns t = read_text_columns(path, "test file", /*title_allowed=*/true);
  EXPECT_EQ(t.title, (std::vector<std::string>{"time", "accel"}));
  ASSERT_EQ(t.rows.size(), 1u);
  const std::string refused = error_of("time,accel\n0 1\n", false);
  EXPECT_NE(refused.find(":1: 'time' is not a finite number"), std::string::npos) << refused;
  const std::string late = error_of("time,accel\n0 1\n1 x\n", true);
  EXPECT_NE(late.find(":3: 'x' is not a finite number"), std::string::npos) << late;
}

TEST(TextColumns, TheNumberRuleIsWholeAndFinite) {
  EXPECT_EQ(core::parse_finite("12"), 12.0);
  EXPECT_EQ(core::parse_finite("-.5"), -0.5);
  EXPECT_EQ(core::parse_finite("1e-3"), 1e-3);
  for (const char* bad : {"", "1.2.3", "nan", "inf", "-inf", "3m", "1e999", " 1"})
    EXPECT_FALSE(core::parse_finite(bad).has_value()) << bad;
  const std::string text = error_of("0 1\n0 nan\n", false);
  EXPECT_NE(text.find("rths_text_columns_bad.txt:2: 'nan'"), std::string::npos) << text;
}

TEST(TextColumns, AFileThatCannotBeOpenedIsNamedWithWhatItWasFor) {
  try {
    read_text_columns("/nonexistent/x.txt", "delay trace");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/x.txt: cannot open delay trace");
  }
}

TEST(TextColumns, NumbersInMessagesAreShort) {
  EXPECT_EQ(core::format_number(0.014), "0.014");
  EXPECT_EQ(core::format_number(1e-5), "1e-05");
  EXPECT_EQ(core::format_number(0.0), "0");
}

}  // namespace
}  // namespace rths::study
