#include "util/plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <unistd.h>

#include "tests/support/png_size.h"

namespace rths::util {
namespace {

using test::png_size;

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

// Min/max decimation keeps every column's extent: a one-sample spike in a million points
// survives, at most four points a column are kept, the ends are kept, a gap stays a gap.
TEST(Plot, DecimationKeepsEveryPeakAndAtMostFourPointsAColumn) {
  Series s{"long", {}, {}};
  const std::size_t n = 1000000;
  for (std::size_t k = 0; k < n; ++k) {
    s.x.push_back(static_cast<double>(k) * 1e-4);
    s.y.push_back(std::sin(0.001 * static_cast<double>(k)));
  }
  s.y[777777] = 50.0;   // a spike
  s.y[123456] = -60.0;  // a dip
  s.y[500000] = std::nan("");
  const std::vector<std::size_t> kept = decimate_min_max(s, 0.0, 100.0, 1000);
  EXPECT_LE(kept.size(), 4u * 1001u + 1u);
  EXPECT_GT(kept.size(), 1000u);
  const std::set<std::size_t> set(kept.begin(), kept.end());
  for (std::size_t k :
       {std::size_t{0}, n - 1, std::size_t{777777}, std::size_t{123456}, std::size_t{500000}})
    EXPECT_EQ(set.count(k), 1u) << k;
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  // A zoom: the points outside collapse to one column each side, those inside keep their extent.
  const std::vector<std::size_t> zoom = decimate_min_max(s, 77.0, 78.0, 100);
  EXPECT_LE(zoom.size(), 4u * 103u + 1u);  // 100 columns, one each side, the gap splits one
  EXPECT_EQ(std::set<std::size_t>(zoom.begin(), zoom.end()).count(777777), 1u);
  // A loop (x not ascending) is kept whole.
  const Series loop{"loop", {0, 1, 0, -1, 0}, {1, 0, -1, 0, 1}};
  EXPECT_EQ(decimate_min_max(loop, -1.0, 1.0, 1).size(), 5u);
  EXPECT_THROW(decimate_min_max(loop, 1.0, 1.0, 1), std::invalid_argument);
}

// A loop (force against displacement) is simplified in the panel's pixels: 100 turns of an ellipse
// at 1000 points a turn keep a few percent of their points, a one-point spike stays, and no dropped
// point is farther than the tolerance from the line drawn.
TEST(Plot, ALoopIsSimplifiedWithinHalfAPixel) {
  Series loop{"loop", {}, {}};
  for (int k = 0; k < 100000; ++k) {
    const double phase = 2.0 * 3.141592653589793 * k / 1000.0;
    loop.x.push_back(std::cos(phase));
    loop.y.push_back(0.5 * std::sin(phase + 0.3));
  }
  loop.y[54321] = 0.9;  // a spike
  const std::vector<std::size_t> kept = simplify_path(loop, -1.0, 1.0, -1.0, 1.0, 1000, 340, 0.5);
  EXPECT_LT(kept.size(), 100000u / 10u) << kept.size();
  EXPECT_EQ(std::set<std::size_t>(kept.begin(), kept.end()).count(54321), 1u);
  EXPECT_EQ(kept.front(), 0u);
  EXPECT_EQ(kept.back(), 99999u);
  const auto px = [&](std::size_t k) { return (loop.x[k] + 1.0) * 500.0; };
  const auto py = [&](std::size_t k) { return (loop.y[k] + 1.0) * 170.0; };
  double worst = 0.0;
  for (std::size_t i = 0; i + 1 < kept.size(); ++i) {
    const std::size_t a = kept[i], b = kept[i + 1];
    const double dx = px(b) - px(a), dy = py(b) - py(a), length2 = dx * dx + dy * dy;
    for (std::size_t k = a + 1; k < b; ++k) {
      const double t = std::clamp(
          length2 > 0 ? ((px(k) - px(a)) * dx + (py(k) - py(a)) * dy) / length2 : 0.0, 0.0, 1.0);
      worst = std::max(worst, std::hypot(px(k) - px(a) - t * dx, py(k) - py(a) - t * dy));
    }
  }
  EXPECT_LE(worst, 0.5);
}

// A figure is complete or absent: gnuplot failing on the plot leaves neither the PNG nor the SVG
// (nor a partial file), where it used to leave an empty PNG; nor is its temporary script left,
// whether it failed or not (TMPDIR is the figure's folder here, so the check sees it).
TEST(Plot, AFailedFigureLeavesNoFile) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_atomic_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const char* tmpdir = std::getenv("TMPDIR");
  const std::string saved = tmpdir ? tmpdir : "";
  setenv("TMPDIR", dir.c_str(), 1);
  PlotSpec broken{"broken", "x", "y", {{"a", {0, 1, 2}, {0, 1, 4}, "no_such_style"}}};
  EXPECT_THROW(write_png_panels({broken}, dir / "broken.png"), std::runtime_error);
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "a failed figure left a file";
  // A long series is drawn decimated, with its spike, into a complete pair of files.
  PlotSpec long_one{"long", "t (s)", "y", {{"a", {}, {}}}};
  for (int k = 0; k < 200000; ++k) {
    long_one.series[0].x.push_back(k * 1e-3);
    long_one.series[0].y.push_back(k == 150000 ? 123.0 : std::sin(k * 1e-2));
  }
  write_png_panels({long_one}, dir / "long.png");
  EXPECT_GT(std::filesystem::file_size(dir / "long.png"), 1000u);
  std::ifstream in(dir / "long.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_LT(svg.size(), 2000000u);  // 200 000 points would take several MB
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_NE(entry.path().extension(), ".gp") << entry.path();
  }
  EXPECT_EQ(files, 2u);
  if (tmpdir)
    setenv("TMPDIR", saved.c_str(), 1);
  else
    unsetenv("TMPDIR");
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

// Stacked panels share an x axis: their data areas line up whatever each legend's width; a
// legend too long for its panel puts every legend of the figure below its panel, outside every
// data area. Read from the SVG: each panel's border is a closed black path "M left,top L
// left,bottom L right,bottom L right,top"; each series' path starts with its legend sample
// "M x,y L x2,y".
TEST(Plot, StackedPanelsLineUpAndALegendTooLongForItsPanelGoesBelow) {
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
  std::set<std::array<double, 4>> areas;  // left, top, bottom, right (each drawn once or twice)
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), border); it != std::sregex_iterator();
       ++it) {
    edges.insert({(*it)[1], (*it)[4]});
    areas.insert(
        {std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3]), std::stod((*it)[4])});
  }
  ASSERT_EQ(edges.size(), 1u) << "the panels' data areas differ";
  ASSERT_EQ(areas.size(), 2u);
  const std::regex sample(R"(stroke='rgb\([^)]*\)'\s+d='M([0-9.]+),([0-9.]+) L[0-9.]+,[0-9.]+ M)");
  int samples = 0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), sample); it != std::sregex_iterator();
       ++it, ++samples) {
    const double x = std::stod((*it)[1]), y = std::stod((*it)[2]);
    for (const auto& a : areas)
      EXPECT_FALSE(x > a[0] && x < a[3] && y > a[1] && y < a[2])
          << "a legend sample inside the data at " << x << "," << y;
  }
  EXPECT_EQ(samples, 3);
  std::filesystem::remove_all(dir);
}

// A legend that fits goes inside the data area, at the corner the data leave empty: a line
// rising from lower left to upper right leaves the top left (SVG y grows downwards).
TEST(Plot, ALegendThatFitsIsInsideAtTheEmptyCorner) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_inside_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::vector<double> x, y;
  for (int k = 0; k <= 100; ++k) {
    x.push_back(k);
    y.push_back(k);
  }
  write_png_plot({"rising", "x (m)", "y (m)", {{"rising line", x, y}}}, dir / "inside.png");
  std::ifstream in(dir / "inside.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::smatch box;
  ASSERT_TRUE(std::regex_search(
      svg, box,
      std::regex(
          R"(stroke='black'\s+d='M([0-9.]+),([0-9.]+) L\1,([0-9.]+) L([0-9.]+),\3 L\4,\2)")));
  const double left = std::stod(box[1]), top = std::stod(box[2]), bottom = std::stod(box[3]),
               right = std::stod(box[4]);
  std::smatch sample;
  ASSERT_TRUE(std::regex_search(
      svg, sample, std::regex(R"(stroke='rgb\([^)]*\)'\s+d='M([0-9.]+),([0-9.]+) L[0-9.]+,\2 )")));
  const double sx = std::stod(sample[1]), sy = std::stod(sample[2]);
  EXPECT_GT(sx, left);
  EXPECT_LT(sx, (left + right) / 2) << "the legend's sample is not on the left half";
  EXPECT_LT(sy, (top + bottom) / 2) << "the legend's sample is not on the upper half";
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

// A bar chart names each bar under it, on as many lines as its label has.
// A narrow panel with max_x_tics 4 over 2 s labels its x axis every 0.5 s (gnuplot's own choice
// there, every 0.2 s, runs the labels together).
TEST(Plot, MaxXTicsLabelsARoundStepThatFitsTheCount) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_tics_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  // y from 0 to 100: its tick labels share none of the x labels looked for.
  PlotSpec spec{"tics", "time (s)", "y", {{"a", {0.0, 0.7, 2.0}, {0.0, 100.0, 50.0}}}};
  spec.width = 450;
  spec.max_x_tics = 4;
  write_png_plot(spec, dir / "tics.png");
  std::ifstream in(dir / "tics.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // gnuplot's "% h" sets a space before a positive number.
  for (const char* label : {"> 0.5<", "> 1.5<"})
    EXPECT_NE(svg.find(label), std::string::npos) << label;
  for (const char* label : {"> 0.2<", "> 0.4<", "> 1.2<"})
    EXPECT_EQ(svg.find(label), std::string::npos) << label;
  std::filesystem::remove_all(dir);
}

TEST(Plot, ABarChartNamesEachBarUnderItOnItsLines) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_bars_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  PlotSpec spec{"bars",
                "",
                "share (%)",
                {{"first", {0.65, 1.35}, {3, 3}, "filledcurves y1=0"},
                 {"second", {1.65, 2.35}, {5, 5}, "filledcurves y1=0"}}};
  spec.x_labels = {{1.0, "actuator 1\nwhole rig"}, {2.0, "load cell 1\noffset_drift"}};
  write_png_plot(spec, dir / "bars.png");
  std::ifstream in(dir / "bars.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* line : {">actuator 1<", ">whole rig<", ">load cell 1<", ">offset_drift<"})
    EXPECT_NE(svg.find(line), std::string::npos) << line;
  std::filesystem::remove_all(dir);
}

// Panels with columns = 2 are a grid, row by row: four 800 x 300 panels make a 1600 x 600 figure
// (one column would be 800 x 1200); a marker near the right edge has its label end at its line.
TEST(Plot, PanelsInColumnsAreAGridAndAMarkerAtTheRightEdgeIsLabelledLeftOfIt) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_grid_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::vector<PlotSpec> panels;
  for (const char* name : {"one", "two", "three", "four"}) {
    PlotSpec p{name, "time (s)", "x (mm)", {{"a", {0, 5, 10}, {0, 1, 0}}}};
    p.height = 300;
    p.columns = 2;
    panels.push_back(p);
  }
  panels[1].markers.push_back({9.8, "limit tripped"});
  panels[2].markers.push_back({1.0, "early stop"});
  write_png_panels(panels, dir / "grid.png");
  EXPECT_EQ(png_size(dir / "grid.png"), (std::pair<std::uint32_t, std::uint32_t>{1600, 600}));
  std::ifstream in(dir / "grid.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto anchor_of = [&](const std::string& label) {
    const auto text = svg.find(">" + label + "<");
    const auto group = svg.rfind("<g ", text);
    return svg.substr(group, text - group).find("text-anchor=\"end\"") != std::string::npos;
  };
  EXPECT_TRUE(anchor_of("limit tripped"));
  EXPECT_FALSE(anchor_of("early stop"));
  std::filesystem::remove_all(dir);
}

// A page of panels that draw the same cases (PlotSpec::one_legend_below, as the actuator pages)
// has one legend below them all: each title once, every entry inside the page's width and below
// the lowest panel; the page grows by the legend's rows.
TEST(Plot, OneLegendBelowAGridNamesEachTitleOnceWithinThePage) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_page_key_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::vector<std::string> cases = {"reference",
                                          "network_60ms_uncompensated",
                                          "network_60ms_predicted",
                                          "network_60ms_linear_model",
                                          "network_60ms_model_30pct_soft",
                                          "network_100ms_predicted",
                                          "link_60ms_predicted",
                                          "sites_predicted",
                                          "sites_uncompensated"};
  std::vector<PlotSpec> panels;
  for (const char* name : {"lab_b: tracking", "lab_b: loop", "lab_c: tracking", "lab_c: loop"}) {
    PlotSpec p{name, "time (s)", "x (mm)"};
    for (std::size_t i = 0; i < cases.size(); ++i)
      p.series.push_back({cases[i], {0, 5, 10}, {0, static_cast<double>(i), 0}});
    p.width = 450;
    p.height = 400;
    p.columns = 4;
    p.one_legend_below = true;
    panels.push_back(p);
  }
  write_png_panels(panels, dir / "page.png");
  const int font = figure_font_points(1800, true);
  const PageLegend legend = page_legend(panels, 1800, font);
  EXPECT_EQ(legend.entries.size(), cases.size());
  const auto [width, height] = png_size(dir / "page.png");
  EXPECT_EQ(width, 1800u);
  EXPECT_EQ(height, static_cast<std::uint32_t>(400 + legend.height_px));
  std::ifstream in(dir / "page.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const std::string& title : cases) {
    const auto text = svg.find(">" + title + "<");
    ASSERT_NE(text, std::string::npos) << title;
    EXPECT_EQ(svg.find(">" + title + "<", text + 1), std::string::npos) << title << " twice";
    const auto at = svg.rfind("translate(", text);
    const double x = std::stod(svg.substr(at + 10));
    const double y = std::stod(svg.substr(svg.find(',', at) + 1));
    EXPECT_GE(x, 0.0) << title;
    EXPECT_LE(x + static_cast<double>(title.size()) * character_pixels(font), 1800.0) << title;
    EXPECT_GT(y, 400.0) << title << ": not below the panels";
    EXPECT_LT(y, static_cast<double>(height)) << title;
  }
  std::filesystem::remove_all(dir);
}

// A legend below whose entry is wider than the figure continues on a line of its own, so no
// entry runs past the right edge (the entry's words all drawn, in order).
TEST(Plot, ALegendEntryWiderThanTheFigureContinuesOnItsOwnLine) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("rths_plot_key_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string long_title =
      "network_60ms_uncompensated (limit tripped at t = 5.113 s, clipped, and far more said)";
  PlotSpec panel{"p", "time (s)", "x (mm)", {{long_title, {0, 1}, {0, 1}}}};
  for (int i = 0; i < 6; ++i) panel.series.push_back({"case " + std::to_string(i), {0, 1}, {1, 0}});
  write_png_panels({panel}, dir / "key.png");
  std::ifstream in(dir / "key.svg");
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(svg.find(">" + long_title + "<"), std::string::npos);
  const auto first = svg.find(">network_60ms_uncompensated (limit tripped at t =");
  const auto rest = svg.find(">  5.113 s, clipped, and far more said)<");
  ASSERT_NE(first, std::string::npos);
  ASSERT_NE(rest, std::string::npos);
  EXPECT_LT(first, rest);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rths::util
