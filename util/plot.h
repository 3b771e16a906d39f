#pragma once
// Plots through gnuplot (Debian's gnuplot-nox, pngcairo and svg terminals): line series to a PNG
// file and the same figure as SVG beside it (name.png -> name.svg), both drawn by one gnuplot
// process.
// The script goes to gnuplot as a private temporary file, removed after (gnuplot reads its stdin a
// byte per system call), the data in it once, as datablocks both terminals draw. Nothing but the
// PNG and the SVG is left, each
// first as "<name>.partial" and renamed into place once gnuplot succeeded: a figure is complete or
// absent (a failed or interrupted plot leaves no file, and an earlier complete one stays).
// A series longer than kPointsPerPixel points per pixel of its panel's width is drawn decimated
// (decimate_min_max; a path whose x is not ascending, simplify_path): no peak is lost, and
// gnuplot's time no longer grows with the record.
// Every figure: fonts legible when printed at a journal's width and each legend inside its panel
// at the corner its data leave emptiest, below the panel only where a legend would take more than
// about half of it (util/plot_layout.h); one colour per series from a 12-colour qualitative
// palette, then the same colours dashed, so no two of the first 48 series look alike.

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "util/plot_layout.h"
#include "util/plot_spec.h"

namespace rths::util {

// The colour ("#4477AA") that the index-th series of a panel takes, so a series on another panel
// of the same figure can name the same colour for the same thing (style "lines lc rgb '...'").
std::string series_colour(std::size_t index);

// At most this many points per pixel of a panel's width are drawn of one series: columns of
// 4 / kPointsPerPixel pixels, each drawn with at most 4 points (decimate_min_max).
inline constexpr int kPointsPerPixel = 2;

// The indices of the points of `s` to draw, ascending, when its x is cut into `buckets` equal
// columns over [x_lo, x_hi] (on log10 x when `log_x`): in each column the first, the smallest y,
// the largest y and the last point, so every column's extent is drawn as it is (min/max
// decimation; at most 4 points a column). Points left or right of the range form one column each
// (the lines into the range stay right, clipped at its edge). A point whose x or y is not finite
// is kept: it ends a line (the gap gnuplot draws). When x is not ascending (a loop, force against
// displacement) every index is kept (simplify_path draws those). @pre buckets > 0, x_lo < x_hi.
std::vector<std::size_t> decimate_min_max(const Series& s, double x_lo, double x_hi, int buckets,
                                          bool log_x = false);

// The indices of the points of a path (x not ascending: a loop, force against displacement) to
// draw, ascending: the path simplified (Ramer-Douglas-Peucker) so that no dropped point lies more
// than `tolerance_px` from the drawn line, in pixels of a panel `width_px` x `height_px` showing
// [x_lo, x_hi] x [y_lo, y_hi]. Every turning point of the loop farther than that from its chord
// stays. A point whose x or y is not finite is kept and ends a line. The path is simplified in
// runs of kSimplifyRun points (each run's ends kept), so a loop of many cycles costs
// O(n kSimplifyRun) at worst, not O(n^2). @pre the ranges are not empty, the sizes > 0.
inline constexpr std::size_t kSimplifyRun = 512;
std::vector<std::size_t> simplify_path(const Series& s, double x_lo, double x_hi, double y_lo,
                                       double y_hi, int width_px, int height_px,
                                       double tolerance_px = 0.5);

// Throws std::runtime_error naming the file when gnuplot is missing or fails.
void write_png_plot(const PlotSpec& spec, const std::filesystem::path& png);

// Several panels stacked vertically in one PNG (shared width), or square ones in a grid (above),
// and the SVG beside it.
void write_png_panels(const std::vector<PlotSpec>& panels, const std::filesystem::path& png);

// Several such figures drawn by one gnuplot process: each gnuplot start-up (cairo, pango, fonts)
// costs about 0.1 s of CPU, more than drawing a decimated figure. Each figure is complete or
// absent as above; when gnuplot fails, none is written (earlier complete ones stay) and the
// message names the first figure.
struct Figure {
  std::vector<PlotSpec> panels;
  std::filesystem::path png;  // the SVG goes beside it
};
void write_png_figures(const std::vector<Figure>& figures);

// Runs a gnuplot script as given (it sets its own terminals and outputs), for figures a PlotSpec
// does not describe (e.g. a heat map with contour lines), as a child process (util/process.h)
// reading the script from a temporary file. Blocks until gnuplot ends (at most 5 minutes).
// `figure` names what it draws, for the message. Throws std::runtime_error naming the figure
// when gnuplot is missing, times out or fails, with the end of gnuplot's own messages.
void run_gnuplot_script(const std::string& script, const std::filesystem::path& figure);

}  // namespace rths::util
