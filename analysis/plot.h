#pragma once
// Plots through gnuplot (Debian's gnuplot-nox, pngcairo terminal): line series to a PNG file.
// Data is streamed inline to gnuplot's stdin; nothing but the PNG is written.

#include <filesystem>
#include <string>
#include <vector>

namespace rths::analysis {

struct Series {
  std::string title;
  std::vector<double> x, y;
  std::string style = "lines";  // gnuplot "with" clause: lines, points, linespoints ...
};

struct PlotSpec {
  std::string title, xlabel, ylabel;
  std::vector<Series> series;
  bool log_y = false;
  int width = 1100, height = 600;  // pixels
};

// Throws std::runtime_error naming the file when gnuplot is missing or fails.
void write_png_plot(const PlotSpec& spec, const std::filesystem::path& png);

// Several panels stacked vertically in one PNG (shared width).
void write_png_panels(const std::vector<PlotSpec>& panels, const std::filesystem::path& png);

}  // namespace rths::analysis
