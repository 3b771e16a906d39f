#include "util/plot_layout.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <string>

namespace rths::util {
namespace {

constexpr double kColumnPoints = 252.0;  // 89 mm
constexpr double kPagePoints = 519.0;    // 183 mm

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool valid() const { return lo < hi; }
};

// The drawn points' extent on each axis, within the panel's own limits where it sets them (on
// log10 of a log axis).
std::pair<Range, Range> drawn_extent(const PlotSpec& spec,
                                     const std::vector<std::vector<std::size_t>>& drawn) {
  Range x, y;
  for (std::size_t i = 0; i < spec.series.size() && i < drawn.size(); ++i)
    for (std::size_t k : drawn[i]) {
      const double px = spec.series[i].x[k], py = spec.series[i].y[k];
      if (!std::isfinite(px) || !std::isfinite(py)) continue;
      if ((spec.log_x && px <= 0) || (spec.log_y && py <= 0)) continue;
      x.add(spec.log_x ? std::log10(px) : px);
      y.add(spec.log_y ? std::log10(py) : py);
    }
  const auto limit = [](bool log, const std::optional<double>& v, double& out) {
    if (v && (!log || *v > 0)) out = log ? std::log10(*v) : *v;
  };
  limit(spec.log_x, spec.x_min, x.lo);
  limit(spec.log_x, spec.x_max, x.hi);
  limit(spec.log_y, spec.y_min, y.lo);
  limit(spec.log_y, spec.y_max, y.hi);
  return {x, y};
}

bool is_top(LegendCorner c) { return c == LegendCorner::top_right || c == LegendCorner::top_left; }
bool is_right(LegendCorner c) {
  return c == LegendCorner::top_right || c == LegendCorner::bottom_right;
}

// Points drawn inside the corner's box of the area x by y.
std::size_t points_in_corner(const PlotSpec& spec,
                             const std::vector<std::vector<std::size_t>>& drawn, LegendCorner c,
                             const Range& x, const Range& y, double width_share,
                             double height_share) {
  const double x_edge =
      is_right(c) ? x.hi - width_share * (x.hi - x.lo) : x.lo + width_share * (x.hi - x.lo);
  const double y_edge =
      is_top(c) ? y.hi - height_share * (y.hi - y.lo) : y.lo + height_share * (y.hi - y.lo);
  std::size_t count = 0;
  for (std::size_t i = 0; i < spec.series.size() && i < drawn.size(); ++i)
    for (std::size_t k : drawn[i]) {
      double px = spec.series[i].x[k], py = spec.series[i].y[k];
      if (!std::isfinite(px) || !std::isfinite(py)) continue;
      if ((spec.log_x && px <= 0) || (spec.log_y && py <= 0)) continue;
      px = spec.log_x ? std::log10(px) : px;
      py = spec.log_y ? std::log10(py) : py;
      if (px < x.lo || px > x.hi || py < y.lo || py > y.hi) continue;
      const bool in_x = is_right(c) ? px >= x_edge : px <= x_edge;
      const bool in_y = is_top(c) ? py >= y_edge : py <= y_edge;
      count += in_x && in_y;
    }
  return count;
}

}  // namespace

int figure_font_points(int width_px, bool page_width) {
  const double print = page_width ? kPagePoints : kColumnPoints;
  const double points = kPrintPoints * width_px / print / kPixelsPerPoint;
  return std::max(kMinimumPoints, static_cast<int>(std::lround(points)));
}

double character_pixels(int font_points) { return 0.55 * kPixelsPerPoint * font_points; }
double line_pixels(int font_points) { return 1.2 * kPixelsPerPoint * font_points; }

LegendPlacement place_legend(const PlotSpec& spec,
                             const std::vector<std::vector<std::size_t>>& drawn, double width_share,
                             double height_share) {
  LegendPlacement out;
  const auto [x, y] = drawn_extent(spec, drawn);
  if (!x.valid() || !y.valid()) return out;
  constexpr std::array<LegendCorner, 4> kOrder = {LegendCorner::top_right, LegendCorner::top_left,
                                                  LegendCorner::bottom_right,
                                                  LegendCorner::bottom_left};
  std::size_t fewest = std::numeric_limits<std::size_t>::max();
  for (LegendCorner c : kOrder) {
    const std::size_t n = points_in_corner(spec, drawn, c, x, y, width_share, height_share);
    if (n < fewest) {
      fewest = n;
      out.corner = c;
    }
  }
  const bool y_fixed = spec.y_min || spec.y_max || spec.log_y;
  if (fewest == 0 || y_fixed || !(height_share > 0 && height_share < 1)) return out;
  const auto padded = padded_y_range(spec.series, {});
  if (!padded) return out;
  const auto [lo, hi] = *padded;
  const double span = (hi - lo) / (1.0 - height_share);
  out.y_range = is_top(out.corner) ? std::make_pair(lo, lo + span) : std::make_pair(hi - span, hi);
  return out;
}

std::pair<double, double> legend_share(const PlotSpec& spec, const FigureLayout& layout) {
  std::size_t longest = 0;
  for (const Series& s : spec.series) longest = std::max(longest, s.title.size());
  const double ch = character_pixels(layout.font), line = line_pixels(layout.font);
  const double width = (static_cast<double>(longest) + 7.0) * ch;
  const double height = (static_cast<double>(spec.series.size()) + 0.6) * line;
  return {width / layout.data_width, height / layout.data_height};
}

FigureLayout figure_layout(const std::vector<PlotSpec>& panels, bool page_width, bool square,
                           int columns, int figure_width) {
  FigureLayout l;
  const PlotSpec& first = panels.front();
  l.font = figure_font_points(figure_width, page_width);
  const double ch = character_pixels(l.font), line = line_pixels(l.font);
  l.panel_width = static_cast<double>(figure_width) / columns;
  const double panel_height = square ? l.panel_width : first.height;
  // Left: the y tick labels (about 7 characters) and the y label; right: a character's gap.
  l.left = 9.0 * ch + line;
  l.right = 2.0 * ch;
  l.data_width = std::max(1.0, l.panel_width - l.left - l.right);
  // Above: a two-line title; below: tick labels and the x label.
  l.data_height = std::max(1.0, (square ? l.data_width : panel_height) - 5.0 * line);
  // A y label runs along the panel's whole height, centred on its data area: a line of it may
  // take that height less a line's margin.
  l.ylabel_chars = static_cast<std::size_t>(
      std::max(8.0, ((square ? l.panel_width : panel_height) - line) / ch));
  std::size_t most_series = 0, longest = 0, ylabel_lines = 1;
  for (const PlotSpec& p : panels) {
    const auto [w, h] = legend_share(p, l);
    if (!p.series.empty() && (w > kInsideWidthShare || h > kInsideHeightShare))
      l.legends_inside = false;
    most_series = std::max(most_series, p.series.size());
    for (const Series& s : p.series) longest = std::max(longest, s.title.size());
    const std::string wrapped = wrap_title(p.ylabel, l.ylabel_chars);
    ylabel_lines = std::max<std::size_t>(
        ylabel_lines,
        1 + static_cast<std::size_t>(std::count(wrapped.begin(), wrapped.end(), '\n')));
  }
  l.left += static_cast<double>(ylabel_lines - 1) * line;
  l.data_width = std::max(1.0, l.panel_width - l.left - l.right);
  if (!l.legends_inside) {
    // Entries as wide as the panel holds, in as many columns as fit; in one column, each entry's
    // lines (split_key_title) are rows of their own.
    const double entry = (static_cast<double>(longest) + 7.0) * ch;
    l.below_columns =
        static_cast<int>(std::max(1.0, std::floor((l.panel_width - 2.0 * ch) / entry)));
    // A margin of two characters each side: the width of a character is an estimate.
    l.key_chars = static_cast<std::size_t>(std::max(8.0, (l.panel_width - 4.0 * ch) / ch - 8.0));
    double rows = 0.0;
    if (l.below_columns > 1) {
      rows = std::ceil(static_cast<double>(most_series) / l.below_columns);
    } else {
      for (const PlotSpec& p : panels) {
        std::size_t lines = 0;
        for (const Series& s : p.series) lines += split_key_title(s.title, l.key_chars).size();
        rows = std::max(rows, static_cast<double>(lines));
      }
    }
    l.legend_below_px = static_cast<int>(std::ceil((rows + 1.5) * line));
  }
  return l;
}

PageLegend page_legend(const std::vector<PlotSpec>& panels, int figure_width, int font_points) {
  PageLegend legend;
  std::set<std::string> shown;
  std::size_t longest = 0;
  for (std::size_t p = 0; p < panels.size(); ++p)
    for (std::size_t i = 0; i < panels[p].series.size(); ++i)
      if (shown.insert(panels[p].series[i].title).second) {
        legend.entries.emplace_back(p, i);
        longest = std::max(longest, panels[p].series[i].title.size());
      }
  const double ch = character_pixels(font_points);
  const double entry = (static_cast<double>(longest) + 7.0) * ch;
  legend.columns = static_cast<int>(std::max(1.0, std::floor((figure_width - 4.0 * ch) / entry)));
  const auto rows = (legend.entries.size() + static_cast<std::size_t>(legend.columns) - 1) /
                    static_cast<std::size_t>(legend.columns);
  legend.height_px =
      static_cast<int>(std::ceil((static_cast<double>(rows) + 1.5) * line_pixels(font_points)));
  return legend;
}

std::vector<std::string> split_key_title(const std::string& title, std::size_t max_chars) {
  std::vector<std::string> lines;
  std::string current;
  std::size_t at = 0;
  while (at < title.size()) {
    const std::size_t space = title.find(' ', at);
    const std::string word =
        title.substr(at, space == std::string::npos ? std::string::npos : space - at);
    at = space == std::string::npos ? title.size() : space + 1;
    if (!current.empty() && current.size() + 1 + word.size() > max_chars) {
      lines.push_back(current);
      current = "  " + word;  // a continuation is indented under its entry
    } else {
      current += (current.empty() ? "" : " ") + word;
    }
  }
  if (!current.empty() || lines.empty()) lines.push_back(current);
  return lines;
}

namespace {

// Words into lines of at most `width` characters (a longer word alone on its line).
std::vector<std::string> fill_lines(const std::vector<std::string>& words, std::size_t width) {
  std::vector<std::string> lines(1);
  for (const std::string& word : words) {
    if (!lines.back().empty() && lines.back().size() + 1 + word.size() > width)
      lines.emplace_back();
    lines.back() += (lines.back().empty() ? "" : " ") + word;
  }
  return lines;
}

}  // namespace

std::string wrap_title(const std::string& title, std::size_t max_chars) {
  std::vector<std::string> words;
  std::size_t total = 0;
  std::istringstream in(title);
  for (std::string word; in >> word; total += word.size() + 1) words.push_back(word);
  std::vector<std::string> lines = fill_lines(words, max_chars);
  // As many lines as needed, of even length: no last line of one word.
  for (std::size_t width = total / lines.size(); lines.size() > 1 && width < max_chars; ++width) {
    if (auto even = fill_lines(words, width); even.size() == lines.size()) {
      lines = std::move(even);
      break;
    }
  }
  std::string out;
  for (const std::string& line : lines) out += (out.empty() ? "" : "\n") + line;
  return out;
}

std::string key_command(LegendCorner corner) {
  const char* where = "top right";
  if (corner == LegendCorner::top_left) where = "top left";
  if (corner == LegendCorner::bottom_right) where = "bottom right";
  if (corner == LegendCorner::bottom_left) where = "bottom left";
  std::string out = "set key inside ";
  out += where;
  out += " vertical Left reverse opaque box\n";
  return out;
}

}  // namespace rths::util
