#pragma once
// How a figure is laid out for print (util/plot.h draws it): the font size that stays legible
// when the figure is printed at a journal's width, and where each panel's legend goes inside
// its data area.
//
// Fonts. A figure is printed at a journal's single column (89 mm = 252 pt) when it is one column
// of panels, and at the full text width (183 mm = 519 pt) when it is a grid of square panels.
// Text must read at least kPrintPoints there. gnuplot's pngcairo draws a font of F pt with an em
// of kPixelsPerPoint F px (measured: a 10 pt sans 'H' is 10 px tall, cap height 0.72 em), so a
// figure W px wide needs
//   F = kPrintPoints W / (print width in pt) / kPixelsPerPoint,  at least kMinimumPoints.
// For the figures' 1100 px: 22 pt in one column, 11 pt in a grid.
//
// Legends. Inside the data area, in the corner the panel's drawn points leave emptiest: each
// corner's box, the legend's size as a share of the data area's width and height, counts the
// points inside it, and the least crowded corner wins (ties in the order top right, top left,
// bottom right, bottom left). Where even that corner holds points and the panel's y range is not
// fixed (no y_min/y_max, linear y), the y range is widened on the legend's side so that the
// legend covers none: with the data spanning [lo, hi] (padded as util::padded_y_range pads) and
// the legend h of the height, the range becomes [lo, lo + (hi - lo) / (1 - h)] for a top corner,
// [hi - (hi - lo) / (1 - h), hi] for a bottom one.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "util/plot_spec.h"

namespace rths::util {

inline constexpr double kPrintPoints = 7.0;      // pt: the smallest text a journal accepts
inline constexpr double kPixelsPerPoint = 1.39;  // px of em per pt in pngcairo's 96-dpi-like scale
inline constexpr int kMinimumPoints = 10;

// The font size (pt) of a figure `width_px` wide, printed at one column (false) or the full text
// width (`page_width`, a grid of square panels).
int figure_font_points(int width_px, bool page_width);

// Approximate sizes of text in that font, in px: an average character's width and a line's
// height (1.2 em).
double character_pixels(int font_points);
double line_pixels(int font_points);

enum class LegendCorner { top_right, top_left, bottom_right, bottom_left };

struct LegendPlacement {
  LegendCorner corner = LegendCorner::top_right;
  // The y range to draw with, set only where the legend needed room (header); else the panel's.
  std::optional<std::pair<double, double>> y_range;
};

// The legend's corner for `spec`, whose legend box takes `width_share` of the data area's width
// and `height_share` of its height (each in (0, 1)). Counts the points drawn (decimated as
// drawn, `drawn` the indices per series, in series order).
LegendPlacement place_legend(const PlotSpec& spec,
                             const std::vector<std::vector<std::size_t>>& drawn, double width_share,
                             double height_share);

// `title` broken at spaces into as few lines of at most `max_chars` characters as it needs, of
// about even length (a longer word keeps a line of its own); runs of spaces become one. Every
// figure's titles go through it, with the width its data area leaves, so that a long title is never
// cut at the figure's left edge.
std::string wrap_title(const std::string& title, std::size_t max_chars);

// gnuplot's "set key inside <corner> ..." for a placement.
std::string key_command(LegendCorner corner);

// How one figure's text and legends are laid out: its font, the data area's pixels of each
// panel, the y label's lines, and whether every legend fits inside its panel; where one does not,
// every legend of the figure goes below its panel, and each panel grows by the legend's lines,
// so its data area keeps its size. A legend below is set in as many columns as the panel's width
// holds of its longest entry; one column (`below_columns` 1) is centred on the panel, and an
// entry wider than the panel continues on lines of its own (split_key_title).
struct FigureLayout {
  int font = kMinimumPoints;                   // pt
  double left = 0.0, right = 0.0;              // px from a panel's edges to its data area
  double data_width = 0.0, data_height = 0.0;  // px of one panel's data area
  double panel_width = 0.0;                    // px
  bool legends_inside = true;
  int legend_below_px = 0;    // px each panel grows by, its legend below it
  int below_columns = 1;      // columns of a legend below
  std::size_t key_chars = 0;  // characters of a line of an entry of a legend below, in one column
  std::size_t ylabel_chars = 0;  // characters of a y label's line: the panel's height
};

// A legend's box as a share of the data area: its longest entry and line sample (4 characters)
// with a border, one line per series.
std::pair<double, double> legend_share(const PlotSpec& spec, const FigureLayout& layout);
// A legend inside may take at most this share of its panel's width and height.
inline constexpr double kInsideWidthShare = 0.6, kInsideHeightShare = 0.45;

// A figure of `panels` `figure_width` px wide in `columns` columns of panels; `page_width`: printed
// at a page's width (a grid), else a column's; `square`: square data areas. The y label takes as
// many lines as the longest one needs at the data area's height (left grows by a line each).
FigureLayout figure_layout(const std::vector<PlotSpec>& panels, bool page_width, bool square,
                           int columns, int figure_width);

// One legend below a grid of panels (PlotSpec::one_legend_below): the series whose titles it
// shows, each title once, in the order the panels first draw them; in as many columns as
// `figure_width` holds of its longest entry (its sample, 4 characters, and gaps), and the px it
// takes below the panels: its rows and a line's margin.
struct PageLegend {
  std::vector<std::pair<std::size_t, std::size_t>> entries;  // panel, series of each title
  int columns = 1;
  int height_px = 0;
};
PageLegend page_legend(const std::vector<PlotSpec>& panels, int figure_width, int font_points);

// A legend entry's title cut at spaces into lines of at most `max_chars` characters (the first
// line keeps as many words as fit): a legend below draws each further line as an entry of its own
// without a sample, since gnuplot draws a title's line breaks over the next entry.
std::vector<std::string> split_key_title(const std::string& title, std::size_t max_chars);

}  // namespace rths::util
