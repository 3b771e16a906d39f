#include "util/plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>

#include <unistd.h>

namespace rths::util {
namespace {

TEST(Plot, WritesThePngAndTheSvgBesideIt) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  PlotSpec top{"top", "x", "y", {{"a", {0, 1, 2}, {0, 1, 4}}}};
  PlotSpec bottom{"bottom",
                  "x",
                  "y (log)",
                  {{"b", {1, 2, 3}, {0.01, 1, 100}}, {"own dash", {1, 3}, {1, 1}, "lines dt 2"}},
                  true};
  top.y_min = 0.0;
  top.y_max = 2.0;  // a clipped panel must not carry its range into the next one
  bottom.markers.push_back({2.0, "critical"});
  write_png_panels({top, bottom}, dir / "figure.png");
  EXPECT_GT(std::filesystem::file_size(dir / "figure.png"), 1000u);
  EXPECT_GT(std::filesystem::file_size(dir / "figure.svg"), 1000u);
  std::filesystem::remove_all(dir);
}

TEST(Plot, RunsAScriptAsGivenAndNamesTheFigureWhenGnuplotFails) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_script_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto svg = dir / "map.svg";
  run_gnuplot_script("set terminal svg\nset output '" + svg.string() + "'\nplot sin(x)\n", svg);
  EXPECT_GT(std::filesystem::file_size(svg), 1000u);
  try {
    run_gnuplot_script("plot no_such_function(x)\n", dir / "broken.png");
    FAIL() << "a failing script passed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.png"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(Plot, PaddedRangeFollowsOnlyTheIncludedFiniteSeries) {
  const std::vector<Series> series = {{"bounded", {0, 1}, {-1.0, 1.0}},
                                      {"diverged", {0, 1}, {1e6, std::nan("")}}};
  const auto r = padded_y_range(series, {0}, 0.1);
  ASSERT_TRUE(r.has_value());
  EXPECT_DOUBLE_EQ(r->first, -1.2);
  EXPECT_DOUBLE_EQ(r->second, 1.2);
  EXPECT_DOUBLE_EQ(padded_y_range(series, {}, 0.0)->second, 1e6);
  EXPECT_FALSE(padded_y_range({{"empty", {}, {}}}, {}).has_value());
}

// Stacked panels share an x axis: their data areas line up whatever each legend's width, and
// every legend sits right of the data. Read from the SVG: each panel's border is a closed black
// path "M left,top L left,bottom L right,bottom L right,top"; each series' path starts with its
// legend sample "M x,y L x2,y".
TEST(Plot, StackedPanelsLineUpWithTheLegendOutsideTheData) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_stack_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  PlotSpec narrow{"short legend", "time (s)", "a (ms)", {{"a", {0, 1, 2}, {0, 1, 4}}}};
  PlotSpec wide{
      "long legend",
      "time (s)",
      "b (ms)",
      {{"a much longer legend entry than the panel above has, to widen its key", {0, 2}, {1, 3}},
       {"another", {0, 2}, {2, 2}}}};
  write_png_panels({narrow, wide}, dir / "stack.png");
  std::ifstream in(dir / "stack.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::regex border(
      R"(stroke='black'\s+d='M([0-9.]+),([0-9.]+) L\1,([0-9.]+) L([0-9.]+),\3 L\4,\2)");
  std::set<std::pair<std::string, std::string>> edges;
  double right = 0.0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), border); it != std::sregex_iterator();
       ++it) {
    edges.insert({(*it)[1], (*it)[4]});
    right = std::stod((*it)[4]);
  }
  ASSERT_EQ(edges.size(), 1u) << "the panels' data areas differ";
  const std::regex sample(R"(stroke='rgb\([^)]*\)'\s+d='M([0-9.]+),[0-9.]+ L[0-9.]+,[0-9.]+ M)");
  int samples = 0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), sample); it != std::sregex_iterator();
       ++it, ++samples)
    EXPECT_GT(std::stod((*it)[1]), right) << "a legend sample inside the data";
  EXPECT_EQ(samples, 3);
  std::filesystem::remove_all(dir);
}

TEST(Plot, WrapTitleBreaksAtSpacesWithinTheWidth) {
  EXPECT_EQ(wrap_title("short title", 40), "short title");
  EXPECT_EQ(wrap_title("aaa bbb ccc ddd", 7), "aaa bbb\nccc ddd");
  EXPECT_EQ(wrap_title("averyverylongword x", 5), "averyverylongword\nx");
  EXPECT_EQ(wrap_title("a  b", 10), "a b");
  EXPECT_EQ(wrap_title("one two three four five six seven", 28),
            "one two three four\nfive six seven");  // not "... six" and "seven"
}

// gnuplot centres a title over the data area: one longer than that area is cut at the figure's
// left edge, so a figure's long title is drawn on several lines, each whole.
TEST(Plot, ALongTitleIsDrawnOnSeveralWholeLines) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_title_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string title =
      "paper_sweep: NRMSE against delay, one curve per period and model (critical delays beyond "
      "the swept range not drawn)";
  PlotSpec spec{title,
                "delay (ms)",
                "NRMSE (%)",
                {{"T = 0.05 s, bilinear (uy = 5 mm, b = 0.1)", {0, 1}, {1, 2}}}};
  write_png_plot(spec, dir / "long.png");
  std::ifstream in(dir / "long.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(svg.find(title), std::string::npos) << "the title on one line";
  const auto first = svg.find(">paper_sweep: NRMSE against delay"), last = svg.find(" drawn)<");
  ASSERT_NE(first, std::string::npos);
  ASSERT_NE(last, std::string::npos);
  // Two lines of about even length: the first ends, the second starts, halfway through.
  const auto first_end = svg.find('<', first), last_start = svg.rfind('>', last);
  EXPECT_NEAR(static_cast<double>(first_end - first), static_cast<double>(last - last_start), 12.0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::util
