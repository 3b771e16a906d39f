#pragma once
// What a figure draws (util/plot.h draws it, util/plot_layout.h lays it out): its series, markers
// and panels, and the y range a panel's series set. Units are the caller's.

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rths::util {

// Series and PlotSpec take their leading fields by constructor (not as aggregates), so a figure
// names what it sets and -Wmissing-field-initializers has nothing to say about the rest.
struct Series {
  Series() = default;
  Series(std::string title, std::vector<double> x, std::vector<double> y,
         std::string style = "lines")
      : title(std::move(title)), x(std::move(x)), y(std::move(y)), style(std::move(style)) {}
  std::string title;
  std::vector<double> x, y;
  std::string style = "lines";  // gnuplot "with" clause: lines, points, linespoints ...
};

// A labelled vertical line across the panel at x (e.g. a critical delay).
struct VerticalMarker {
  double x = 0.0;
  std::string label;
};

struct PlotSpec {
  PlotSpec() = default;
  PlotSpec(std::string title, std::string xlabel, std::string ylabel,
           std::vector<Series> series = {}, bool log_y = false)
      : title(std::move(title)),
        xlabel(std::move(xlabel)),
        ylabel(std::move(ylabel)),
        series(std::move(series)),
        log_y(log_y) {}
  std::string title, xlabel, ylabel;
  std::vector<Series> series;
  bool log_y = false;
  // Pixels. A figure is laid out for a journal's column (util/plot_layout.h): at 800 px its font
  // is 16 pt, 7 pt when printed 89 mm wide.
  int width = 800, height = 480;
  bool log_x = false;
  // Axis range; empty = gnuplot's autoscale. Set it so one diverged series cannot flatten the rest
  // (points outside are clipped, not dropped from the legend).
  std::optional<double> x_min, x_max, y_min, y_max;
  std::vector<VerticalMarker> markers;
  // gnuplot format of the y tick labels (e.g. "%g": 1e-05 rather than 0.000010); empty = default.
  std::string y_format;
  // Tick labels at these x (a bar chart's bars: "\n" breaks a label into lines); empty = the
  // numbers of the x axis.
  std::vector<std::pair<double, std::string>> x_labels;
  // At most this many intervals between labelled x tics, each a round step (1, 2 or 5 x 10^k)
  // over the panel's x range (a narrow panel, whose labels gnuplot would run together); 0:
  // gnuplot's own.
  int max_x_tics = 0;
  // A square data area (a force-displacement loop, which runs from lower left to upper right,
  // reads true only with equal axes lengths). A figure of square panels lays them out in a grid
  // of at most two columns, each 5/8 of `width` pixels square, instead of stacking them.
  bool square = false;
  // The first panel's value lays out a figure of panels that are not square: 1, one column of
  // them printed at a column's width; more, a grid of that many columns, row by row, each panel
  // `width` x `height` px, printed at a page's width (a pair of panels per row: one thing's two
  // views side by side).
  int columns = 1;
  // The first panel's value, in a grid of panels (columns > 1): one legend for the figure, below
  // every panel, each title once (drawn as its first series of that title), and none in a panel;
  // for panels that draw the same things in the same colours (a page of actuators, every case on
  // each), whose legends would repeat and crowd the page.
  bool one_legend_below = false;
};

// The range [lo, hi] padded by `margin` of its span on each side, over the finite y of the series
// (all when `include` is empty, else those whose index is listed). Empty when nothing is finite.
std::optional<std::pair<double, double>> padded_y_range(const std::vector<Series>& series,
                                                        const std::vector<std::size_t>& include,
                                                        double margin = 0.08);

}  // namespace rths::util
