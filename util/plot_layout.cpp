#include "util/plot_layout.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

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
