#include "analysis/plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <unistd.h>

namespace rths::analysis {
namespace {

TEST(Plot, WritesThePngAndTheSvgBesideIt) {
  const auto dir = std::filesystem::temp_directory_path() / ("rths_plot_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  PlotSpec top{"top", "x", "y", {{"a", {0, 1, 2}, {0, 1, 4}}}};
  PlotSpec bottom{"bottom", "x", "y (log)", {{"b", {1, 2, 3}, {0.01, 1, 100}}, {"own dash", {1, 3}, {1, 1}, "lines dt 2"}}, true};
  top.y_min = 0.0;
  top.y_max = 2.0;  // a clipped panel must not carry its range into the next one
  bottom.markers.push_back({2.0, "critical"});
  write_png_panels({top, bottom}, dir / "figure.png");
  EXPECT_GT(std::filesystem::file_size(dir / "figure.png"), 1000u);
  EXPECT_GT(std::filesystem::file_size(dir / "figure.svg"), 1000u);
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

}  // namespace
}  // namespace rths::analysis
