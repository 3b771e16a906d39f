#include "util/plot_layout.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace rths::util {
namespace {

std::vector<std::vector<std::size_t>> every_point(const PlotSpec& spec) {
  std::vector<std::vector<std::size_t>> drawn;
  for (const Series& s : spec.series) {
    drawn.emplace_back();
    for (std::size_t k = 0; k < s.x.size(); ++k) drawn.back().push_back(k);
  }
  return drawn;
}

// 7 pt printed: a figure of 1100 px is 22 pt in one column (89 mm), 11 pt across a page's
// width (183 mm); a small figure keeps the 10 pt floor.
TEST(PlotLayout, TheFontReadsSevenPointsAtTheJournalsWidth) {
  EXPECT_EQ(figure_font_points(800, false), 16);
  EXPECT_EQ(figure_font_points(1100, false), 22);
  EXPECT_EQ(figure_font_points(1100, true), 11);
  EXPECT_EQ(figure_font_points(300, false), 10);
  for (int width : {800, 1100, 1600}) {
    const double printed_em =
        figure_font_points(width, false) * kPixelsPerPoint * 252.0 / width;  // pt
    EXPECT_NEAR(printed_em, kPrintPoints, 0.25) << width;
  }
}

TEST(PlotLayout, ALegendGoesToTheCornerTheDataLeaveEmpty) {
  std::vector<double> x, rising, falling;
  for (int k = 0; k <= 100; ++k) {
    x.push_back(k);
    rising.push_back(k);
    falling.push_back(100 - k);
  }
  const PlotSpec up{"", "", "", {{"up", x, rising}}};
  EXPECT_EQ(place_legend(up, every_point(up), 0.3, 0.2).corner, LegendCorner::top_left);
  EXPECT_FALSE(place_legend(up, every_point(up), 0.3, 0.2).y_range.has_value());
  const PlotSpec down{"", "", "", {{"down", x, falling}}};
  EXPECT_EQ(place_legend(down, every_point(down), 0.3, 0.2).corner, LegendCorner::top_right);
}

// A time history that fills every corner: the y range grows on the legend's side by its height,
// so no point lies under it.
TEST(PlotLayout, ALegendOverDataMakesRoomAboveIt) {
  std::vector<double> t, y;
  for (int k = 0; k <= 2000; ++k) {
    t.push_back(k * 0.01);
    y.push_back(std::sin(k * 0.05));
  }
  const PlotSpec wave{"", "time (s)", "u (m)", {{"u", t, y}}};
  const LegendPlacement place = place_legend(wave, every_point(wave), 0.3, 0.25);
  ASSERT_TRUE(place.y_range.has_value());
  const auto [lo, hi] = *place.y_range;
  const bool top =
      place.corner == LegendCorner::top_left || place.corner == LegendCorner::top_right;
  if (top) {
    EXPECT_GE(hi - 0.25 * (hi - lo), 1.0) << "the legend covers the wave's crests";
    EXPECT_LE(lo, -1.0);
  } else {
    EXPECT_LE(lo + 0.25 * (hi - lo), -1.0) << "the legend covers the wave's troughs";
    EXPECT_GE(hi, 1.0);
  }
  // A fixed range is left as the panel sets it.
  PlotSpec fixed = wave;
  fixed.y_min = -1.0;
  fixed.y_max = 1.0;
  EXPECT_FALSE(place_legend(fixed, every_point(fixed), 0.3, 0.25).y_range.has_value());
}

TEST(PlotLayout, TheKeyCommandNamesItsCorner) {
  EXPECT_EQ(key_command(LegendCorner::bottom_left),
            "set key inside bottom left vertical Left reverse opaque box\n");
}

// A legend entry wider than its panel goes on, indented, on lines of its own; no line is longer
// than asked and no word is lost or cut.
TEST(PlotLayout, ALongKeyTitleIsSplitAtSpacesIntoLinesThatFit) {
  const std::string title = "network_60ms_uncompensated (limit tripped at t = 5.113 s, clipped)";
  const std::vector<std::string> lines = split_key_title(title, 40);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "network_60ms_uncompensated (limit");
  EXPECT_EQ(lines[1], "  tripped at t = 5.113 s, clipped)");
  EXPECT_EQ(split_key_title("short", 40), std::vector<std::string>{"short"});
  for (std::size_t width : {12u, 20u, 33u}) {
    std::string joined;
    for (const std::string& line : split_key_title(title, width)) {
      EXPECT_LE(line.size(), std::max<std::size_t>(width, 28)) << line;  // a word longer stays
      joined += (joined.empty() ? "" : " ") + line.substr(line.rfind("  ", 0) == 0 ? 2 : 0);
    }
    EXPECT_EQ(joined, title) << width;
  }
}

// A y label longer than its panel is tall (a 340 px panel at 16 pt holds about 25 characters)
// takes two lines, and the data area moves right by one line to hold them.
TEST(PlotLayout, AYLabelLongerThanItsPanelTakesTwoLinesAndTheMarginGrows) {
  PlotSpec short_label{"t", "time (s)", "x (mm)", {{"a", {0, 1}, {0, 1}}}};
  PlotSpec long_label = short_label;
  long_label.ylabel = "displacement at lab_b, element 1 (mm)";
  short_label.height = long_label.height = 340;
  const FigureLayout one = figure_layout({short_label}, false, false, 1, 800);
  const FigureLayout two = figure_layout({long_label}, false, false, 1, 800);
  EXPECT_EQ(one.ylabel_chars, two.ylabel_chars);
  EXPECT_LT(long_label.ylabel.size(), 2 * one.ylabel_chars);
  EXPECT_GT(long_label.ylabel.size(), one.ylabel_chars);
  EXPECT_NEAR(two.left - one.left, line_pixels(one.font), 1e-9);
  EXPECT_NE(wrap_title(long_label.ylabel, two.ylabel_chars).find('\n'), std::string::npos);
}

}  // namespace
}  // namespace rths::util
