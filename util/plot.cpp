#include "util/plot.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "util/plot_layout.h"
#include "util/process.h"

namespace rths::util {
namespace {

// Paul Tol's "muted" and "bright" qualitative schemes: distinguishable, colour-blind safe.
constexpr const char* kPalette[] = {"#4477AA", "#EE6677", "#228833", "#CCBB44",
                                    "#66CCEE", "#AA3377", "#332288", "#117733",
                                    "#882255", "#999933", "#DDCC77", "#BBBBBB"};
constexpr int kColours = sizeof(kPalette) / sizeof(kPalette[0]);
constexpr int kDashTypes = 4;

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// How many characters of a title fit over the data area, with a margin.
std::size_t title_chars(const FigureLayout& layout) {
  return static_cast<std::size_t>(
      std::max(20.0, (layout.data_width - 20.0) / character_pixels(layout.font)));
}

std::string range(const std::optional<double>& lo, const std::optional<double>& hi) {
  std::ostringstream out;
  out.precision(10);
  out << "[";
  if (lo) out << *lo;
  out << ":";
  if (hi) out << *hi;
  out << "]";
  return out.str();
}

// The points of `s` drawn on `spec`'s panel: all when there are at most kPointsPerPixel per pixel
// of its width, else decimate_min_max over its x range (the panel's, else the series' own).
std::vector<std::size_t> drawn_points(const PlotSpec& spec, const Series& s) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  std::vector<std::size_t> all;
  const int buckets = std::max(1, spec.width * kPointsPerPixel / 4);
  if (n <= 4 * static_cast<std::size_t>(buckets)) {
    all.resize(n);
    for (std::size_t k = 0; k < n; ++k) all[k] = k;
    return all;
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(s.x[k]) || (spec.log_x && s.x[k] <= 0)) continue;
    lo = std::min(lo, s.x[k]);
    hi = std::max(hi, s.x[k]);
  }
  if (spec.x_min) lo = *spec.x_min;
  if (spec.x_max) hi = *spec.x_max;
  if (!(lo < hi) || (spec.log_x && !(lo > 0))) {
    all.resize(n);
    for (std::size_t k = 0; k < n; ++k) all[k] = k;
    return all;
  }
  bool ascending = true;
  for (std::size_t k = 1; k < n && ascending; ++k)
    ascending = !(std::isfinite(s.x[k]) && std::isfinite(s.x[k - 1]) && s.x[k] < s.x[k - 1]);
  if (ascending || spec.log_x || spec.log_y)
    return decimate_min_max(s, lo, hi, buckets, spec.log_x);
  // A loop: simplified in the panel's pixels, its y range the panel's or the series' own.
  double y_lo = std::numeric_limits<double>::infinity(), y_hi = -y_lo;
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(s.y[k])) continue;
    y_lo = std::min(y_lo, s.y[k]);
    y_hi = std::max(y_hi, s.y[k]);
  }
  if (spec.y_min) y_lo = *spec.y_min;
  if (spec.y_max) y_hi = *spec.y_max;
  if (!(y_lo < y_hi)) {
    all.resize(n);
    for (std::size_t k = 0; k < n; ++k) all[k] = k;
    return all;
  }
  return simplify_path(s, lo, hi, y_lo, y_hi, spec.width, std::max(1, spec.height));
}

// The datablock holding series `series` of panel `panel` of figure `tag` (figure_data).
std::string block_name(const std::string& tag, std::size_t panel, std::size_t series) {
  std::string name = "$";
  name += tag;
  name += 'p';
  name += std::to_string(panel);
  name += 's';
  name += std::to_string(series);
  return name;
}

// Every series' drawn points as gnuplot datablocks, once for both terminals of a figure (each
// terminal re-reading the points inline doubled gnuplot's parsing and the simplification).
std::string figure_data(const std::vector<PlotSpec>& panels, const std::string& tag) {
  std::ostringstream data;
  data.precision(10);
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const PlotSpec& spec = panels[p];
    for (std::size_t i = 0; i < spec.series.size(); ++i) {
      const Series& s = spec.series[i];
      data << block_name(tag, p, i) << " << EOD\n";
      for (std::size_t k : drawn_points(spec, s)) {
        // gnuplot cannot draw non-finite points (and zero on a log axis); leave a gap instead.
        if (std::isfinite(s.x[k]) && std::isfinite(s.y[k]) && !(spec.log_y && s.y[k] <= 0) &&
            !(spec.log_x && s.x[k] <= 0)) {
          data << s.x[k] << ' ' << s.y[k] << '\n';
        } else {
          data << '\n';
        }
      }
      data << "EOD\n";
    }
  }
  return data.str();
}

// The x range `spec` draws: its own where set, else its series' finite x.
std::pair<double, double> drawn_x_range(const PlotSpec& spec) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Series& s : spec.series)
    for (double x : s.x)
      if (std::isfinite(x)) {
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
  return {spec.x_min.value_or(lo), spec.x_max.value_or(hi)};
}

// A round step, 1, 2 or 5 x 10^k, that cuts `span` (> 0) into at most `most` intervals.
double round_tic_step(double span, int most) {
  const double raw = span / most;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * decade >= raw * (1.0 - 1e-9)) return m * decade;
  return 10.0 * decade;
}

// The x axis's ticks: the spec's labels at their x, with a bottom margin of their lines and of
// `legend_rows` (a legend below the panel, which a set margin must hold too), or numbers every
// round step of at most max_x_tics intervals, else gnuplot's numbers; gnuplot's margin for both.
std::string x_tics(const PlotSpec& spec, int legend_rows) {
  if (spec.x_labels.empty()) {
    const auto [lo, hi] = drawn_x_range(spec);
    if (spec.max_x_tics <= 0 || spec.log_x || !(lo < hi) || !std::isfinite(hi - lo))
      return "set xtics autofreq\nset bmargin\n";
    std::ostringstream out;
    out.precision(10);
    out << "set xtics " << round_tic_step(hi - lo, spec.max_x_tics) << "\nset bmargin\n";
    return out.str();
  }
  std::ostringstream out;
  out.precision(10);
  std::size_t lines = 1;
  out << "set xtics (";
  for (std::size_t i = 0; i < spec.x_labels.size(); ++i) {
    const std::string& label = spec.x_labels[i].second;
    lines = std::max<std::size_t>(lines, 1 + std::count(label.begin(), label.end(), '\n'));
    out << (i ? ", " : "") << quoted(label) << " " << spec.x_labels[i].first;
  }
  out << ")\nset bmargin " << lines + 2 + static_cast<std::size_t>(legend_rows) << "\n";
  return out.str();
}

// The lines a legend below the panel takes (0 for one inside).
int legend_rows(const FigureLayout& layout) {
  return static_cast<int>(std::lround(layout.legend_below_px / line_pixels(layout.font)));
}

// The legend's command and the y range for `spec`: inside at its emptiest corner (with room made
// for it where it needs some), or below the panel where the figure's layout says so.
std::pair<std::string, std::string> legend_and_y_range(const PlotSpec& spec,
                                                       const FigureLayout& layout) {
  std::string y_range = spec.y_min || spec.y_max ? "set yrange " + range(spec.y_min, spec.y_max)
                                                 : std::string("set autoscale y");
  if (spec.one_legend_below) return {"unset key\n", y_range + "\n"};  // the figure's, below
  if (!layout.legends_inside)
    return {layout.below_columns > 1
                ? "set key outside below center horizontal Left reverse\n"
                : "set key outside below center vertical Left reverse maxcols 1\n",
            y_range + "\n"};
  std::vector<std::vector<std::size_t>> drawn;
  for (const Series& s : spec.series) drawn.push_back(drawn_points(spec, s));
  const auto [width, height] = legend_share(spec, layout);
  const LegendPlacement place = place_legend(spec, drawn, width, height);
  if (place.y_range) y_range = "set yrange " + range(place.y_range->first, place.y_range->second);
  return {key_command(place.corner), y_range + "\n"};
}

// Whether marker m's label fits between its line and the data area's right edge; else it is set
// left of the line, ending there.
bool label_fits_right(const PlotSpec& spec, const VerticalMarker& m, const FigureLayout& layout) {
  const auto [lo, hi] = drawn_x_range(spec);
  if (!(lo < hi) || spec.log_x) return true;
  const double room = (hi - m.x) / (hi - lo) * layout.data_width;
  return static_cast<double>(m.label.size() + 2) * character_pixels(layout.font - 1) <= room;
}

// " title ..." of a series: in a one-column legend below, an entry wider than the panel goes on
// as entries of its own without a sample (gnuplot would draw a title's line break over the next
// entry).
void append_key_title(std::ostringstream& script, const std::string& title,
                      const FigureLayout& layout) {
  if (layout.legends_inside || layout.below_columns > 1) {
    script << " title " << quoted(title);
    return;
  }
  const std::vector<std::string> lines = split_key_title(title, layout.key_chars);
  script << " title " << quoted(lines.front());
  for (std::size_t i = 1; i < lines.size(); ++i)
    script << ", keyentry with lines lc rgb '#FFFFFF' title " << quoted(lines[i]);
}

// " with <style>" of series i of `spec`, in the palette's colour and dash of its index where its
// style names neither (gnuplot refuses an option given twice).
std::string with_style(const PlotSpec& spec, std::size_t i) {
  const std::string& style = spec.series[i].style;
  const auto has = [&](const char* option) {
    return (" " + style + " ").find(option) != std::string::npos;
  };
  std::string out = " with " + style;
  if (!has(" lc ") && !has(" linecolor "))
    out += std::string(" lc rgb '") + kPalette[static_cast<int>(i) % kColours] + "'";
  if (!has(" dt ") && !has(" dashtype "))
    out += " dt " + std::to_string((static_cast<int>(i) / kColours) % kDashTypes + 1);
  return out;
}

void append_panel(std::ostringstream& script, const PlotSpec& spec, const std::string& tag,
                  std::size_t panel, const FigureLayout& layout) {
  const auto [key, y_range] = legend_and_y_range(spec, layout);
  script << (spec.square ? "set size square\n" : "set size nosquare\n") << key << "set title "
         << quoted(wrap_title(spec.title, title_chars(layout))) << "\n"
         << "set xlabel " << quoted(spec.xlabel) << "\n"
         << "set ylabel " << quoted(wrap_title(spec.ylabel, layout.ylabel_chars)) << "\n"
         << (spec.log_y ? "set logscale y\n" : "unset logscale y\n")
         << (spec.log_x ? "set logscale x\n" : "unset logscale x\n")
         // "[:]" would keep the previous panel's range: autoscale instead.
         << (spec.x_min || spec.x_max ? "set xrange " + range(spec.x_min, spec.x_max)
                                      : "set autoscale x")
         << "\n"
         << y_range << "set format y " << quoted(spec.y_format.empty() ? "% h" : spec.y_format)
         << "\n"
         << x_tics(spec, legend_rows(layout)) << "unset arrow\nunset label\n";
  script.precision(10);
  for (std::size_t i = 0; i < spec.markers.size(); ++i) {
    const VerticalMarker& m = spec.markers[i];
    script << "set arrow from first " << m.x << ", graph 0 to first " << m.x
           << ", graph 1 nohead dt 2 lw 1.5 lc rgb '#444444'\n"
           << "set label " << quoted(m.label) << " at first " << m.x << ", graph "
           << 0.97 - 0.05 * static_cast<double>(i % 6)
           << (label_fits_right(spec, m, layout) ? " left offset 0.5,0" : " right offset -0.5,0")
           << " font 'sans," << layout.font - 1 << "'\n";
  }
  script << "plot ";
  for (std::size_t i = 0; i < spec.series.size(); ++i) {
    script << (i ? ", " : "") << block_name(tag, panel, i) << " using 1:2" << with_style(spec, i);
    append_key_title(script, spec.series[i].title, layout);
  }
  script << "\n";
}

// The figure's one legend (PlotSpec::one_legend_below) in the strip below its panels, of a
// figure `height` px tall: each entry drawn as its series is.
void append_page_legend(std::ostringstream& script, const std::vector<PlotSpec>& panels,
                        const PageLegend& legend, int height) {
  script << "set origin 0,0\nset size 1," << static_cast<double>(legend.height_px) / height
         << "\nunset border\nunset tics\nunset grid\nunset title\nunset xlabel\nunset ylabel\n"
         << "unset arrow\nunset label\nunset logscale\nset margins 0,0,0,0\n"
         << "set xrange [0:1]\nset yrange [0:1]\nset key inside center center horizontal Left "
         << "reverse maxcols " << legend.columns << "\n"
         << "plot NaN notitle";  // gnuplot 5.4 fails an assertion on key entries alone
  for (const auto& [p, i] : legend.entries)
    script << ", keyentry" << with_style(panels[p], i) << " title "
           << quoted(panels[p].series[i].title);
  script << "\n";
}

// The terminal, output and common settings of a figure `width` x `height` px in `layout`'s font.
void start_figure(std::ostringstream& script, const std::string& terminal,
                  const std::filesystem::path& file, int width, int height,
                  const FigureLayout& layout) {
  // One gnuplot may draw several figures: none inherits another's margins or ranges.
  script << "reset\n"
         << "set terminal " << terminal << " size " << width << "," << height << " font 'sans,"
         << layout.font << "'\n"
         << "set output " << quoted(file.string()) << "\n"
         << "set termoption noenhanced\nset grid\n";
}

// Square panels (PlotSpec::square) in a grid of at most two columns, each 5/8 of the panels'
// width square (500 px of the default 800): a pair printed across a page's width is a column's
// width each, and their legends fit inside.
std::string square_grid(const std::vector<PlotSpec>& panels, const std::string& tag,
                        const std::string& terminal, const std::filesystem::path& file) {
  const int columns = static_cast<int>(std::min<std::size_t>(2, panels.size()));
  const int rows = static_cast<int>((panels.size() + 1) / 2);
  const int side = panels.front().width * 5 / 8, width = side * columns;
  const FigureLayout layout = figure_layout(panels, true, true, columns, width);
  std::ostringstream script;
  start_figure(script, terminal, file, width, (side + layout.legend_below_px) * rows, layout);
  script << "set multiplot layout " << rows << "," << columns << "\n";
  for (std::size_t p = 0; p < panels.size(); ++p) append_panel(script, panels[p], tag, p, layout);
  script << "unset multiplot\nset output\n";
  return script.str();
}

// Panels in a grid of the first panel's `columns`, row by row, each its `width` x `height` px
// (with its legend below where the layout puts it, or the figure's one legend below them all),
// printed at a page's width.
std::string panel_grid(const std::vector<PlotSpec>& panels, const std::string& tag,
                       const std::string& terminal, const std::filesystem::path& file) {
  const std::size_t columns = std::min<std::size_t>(panels.front().columns, panels.size());
  const std::size_t rows = (panels.size() + columns - 1) / columns;
  const int width = panels.front().width * static_cast<int>(columns);
  FigureLayout layout = figure_layout(panels, true, false, static_cast<int>(columns), width);
  PageLegend legend;
  if (panels.front().one_legend_below) {
    legend = page_legend(panels, width, layout.font);
    layout.legends_inside = true;  // no panel draws one
    layout.legend_below_px = 0;
  }
  const int panel_height = panels.front().height + layout.legend_below_px;
  const int height = panel_height * static_cast<int>(rows) + legend.height_px;
  std::ostringstream script;
  start_figure(script, terminal, file, width, height, layout);
  script << "set multiplot\n";
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const double top = static_cast<double>(p / columns + 1) * panel_height;
    script << "set origin " << static_cast<double>(p % columns) / columns << ","
           << (height - top) / height << "\nset size " << 1.0 / columns << ","
           << static_cast<double>(panel_height) / height << "\n";
    append_panel(script, panels[p], tag, p, layout);
  }
  if (!legend.entries.empty()) append_page_legend(script, panels, legend, height);
  script << "unset multiplot\nset output\n";
  return script.str();
}

std::string figure(const std::vector<PlotSpec>& panels, const std::string& tag,
                   const std::string& terminal, const std::filesystem::path& file) {
  if (std::all_of(panels.begin(), panels.end(), [](const PlotSpec& p) { return p.square; }))
    return square_grid(panels, tag, terminal, file);
  if (panels.front().columns > 1 && panels.size() > 1)
    return panel_grid(panels, tag, terminal, file);
  const FigureLayout layout = figure_layout(panels, false, false, 1, panels.front().width);
  std::ostringstream script;
  const int width = panels.front().width;
  const int panel_height = panels.front().height + layout.legend_below_px;
  start_figure(script, terminal, file, width, panel_height * static_cast<int>(panels.size()),
               layout);
  // Every panel has the same margins, so stacked panels' data areas line up whatever their
  // tick labels.
  script.precision(4);
  script << "set lmargin at screen " << layout.left / width << "\nset rmargin at screen "
         << 1.0 - layout.right / width << "\n";
  if (panels.size() > 1) script << "set multiplot layout " << panels.size() << ",1\n";
  for (std::size_t p = 0; p < panels.size(); ++p) append_panel(script, panels[p], tag, p, layout);
  if (panels.size() > 1) script << "unset multiplot\n";
  script << "set output\n";
  return script.str();
}

// A figure set that takes longer than this is stuck (a 1-minute record draws in seconds).
constexpr std::chrono::seconds kGnuplotTimeout{300};

}  // namespace

void run_gnuplot_script(const std::string& script, const std::filesystem::path& figure) {
  // gnuplot reads a script on its stdin one byte per read(2), a system call per byte of inline
  // data (three quarters of its time for a figure of 10^5 points); from a file it reads buffered.
  // So the script goes to a private temporary file, removed whatever happens, and gnuplot runs
  // through the one child-process unit (util/process.h), its messages kept for the error.
  std::string script_path =
      (std::filesystem::temp_directory_path() / "rths-plot-XXXXXX.gp").string();
  const int fd = mkstemps(script_path.data(), 3);
  if (fd < 0)
    throw std::runtime_error("cannot write the gnuplot script for " + figure.string() + ": " +
                             std::strerror(errno));
  struct RemoveOnExit {
    std::string path;
    ~RemoveOnExit() { std::remove(path.c_str()); }
  } remove_script{script_path};
  std::size_t written = 0;
  while (written < script.size()) {
    const ssize_t n = ::write(fd, script.data() + written, script.size() - written);
    if (n <= 0) break;
    written += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (written != script.size())
    throw std::runtime_error("cannot write the gnuplot script for " + figure.string());
  CommandResult result;
  try {
    result = run_command({"gnuplot", script_path}, kGnuplotTimeout);
  } catch (const std::exception& e) {
    throw std::runtime_error("gnuplot could not draw " + figure.string() + ": " + e.what() +
                             " (is gnuplot-nox installed?)");
  }
  if (!result.ok()) {
    constexpr std::size_t kTail = 600;
    const std::string& out = result.output;
    throw std::runtime_error("gnuplot failed to write " + figure.string() + " (exit " +
                             std::to_string(result.exit_code) + "): " +
                             (out.size() > kTail ? "..." + out.substr(out.size() - kTail) : out));
  }
}

std::string series_colour(std::size_t index) { return kPalette[index % kColours]; }

void write_png_plot(const PlotSpec& spec, const std::filesystem::path& png) {
  write_png_panels({spec}, png);
}

std::vector<std::size_t> decimate_min_max(const Series& s, double x_lo, double x_hi, int buckets,
                                          bool log_x) {
  if (buckets <= 0 || !(x_lo < x_hi))
    throw std::invalid_argument("decimate_min_max: needs buckets > 0 and x_lo < x_hi");
  const std::size_t n = std::min(s.x.size(), s.y.size());
  std::vector<std::size_t> kept;
  const auto position = [log_x](double x) { return log_x ? std::log10(x) : x; };
  const double lo = position(x_lo), width = position(x_hi) - lo;
  // Column of a finite point: -1 left of the range, `buckets` right of it.
  const auto column = [&](double x) -> long {
    const double at = (position(x) - lo) / width * buckets;
    if (!(at >= 0.0)) return -1;
    return std::min<long>(static_cast<long>(at), buckets);
  };
  for (std::size_t k = 1; k < n; ++k)
    if (std::isfinite(s.x[k]) && std::isfinite(s.x[k - 1]) && s.x[k] < s.x[k - 1]) {
      kept.resize(n);  // not ascending: a loop has no columns to keep the extent of
      for (std::size_t i = 0; i < n; ++i) kept[i] = i;
      return kept;
    }
  // The open column: its first, smallest, largest and last point.
  bool open = false;
  long current = 0;
  std::size_t first = 0, low = 0, high = 0, last = 0;
  const auto close = [&] {
    if (!open) return;
    std::size_t four[4] = {first, low, high, last};
    std::sort(std::begin(four), std::end(four));
    for (std::size_t i = 0; i < 4; ++i)
      if (i == 0 || four[i] != four[i - 1]) kept.push_back(four[i]);
    open = false;
  };
  for (std::size_t k = 0; k < n; ++k) {
    const bool finite = std::isfinite(s.x[k]) && std::isfinite(s.y[k]) && !(log_x && s.x[k] <= 0);
    if (!finite) {
      close();
      kept.push_back(k);  // the gap
      continue;
    }
    const long c = column(s.x[k]);
    if (open && c != current) close();
    if (!open) {
      open = true;
      current = c;
      first = low = high = last = k;
      continue;
    }
    last = k;
    if (s.y[k] < s.y[low]) low = k;
    if (s.y[k] > s.y[high]) high = k;
  }
  close();
  return kept;
}

std::vector<std::size_t> simplify_path(const Series& s, double x_lo, double x_hi, double y_lo,
                                       double y_hi, int width_px, int height_px,
                                       double tolerance_px) {
  if (!(x_lo < x_hi) || !(y_lo < y_hi) || width_px <= 0 || height_px <= 0)
    throw std::invalid_argument("simplify_path: needs non-empty ranges and sizes > 0");
  const std::size_t n = std::min(s.x.size(), s.y.size());
  const double sx = width_px / (x_hi - x_lo), sy = height_px / (y_hi - y_lo);
  const auto px = [&](std::size_t k) { return (s.x[k] - x_lo) * sx; };
  const auto py = [&](std::size_t k) { return (s.y[k] - y_lo) * sy; };
  // Squared distance (px^2) of point k from the segment a-b.
  const auto distance2 = [&](std::size_t k, std::size_t a, std::size_t b) {
    const double ax = px(a), ay = py(a), dx = px(b) - ax, dy = py(b) - ay;
    const double length2 = dx * dx + dy * dy;
    double t = length2 > 0.0 ? ((px(k) - ax) * dx + (py(k) - ay) * dy) / length2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    const double ex = px(k) - (ax + t * dx), ey = py(k) - (ay + t * dy);
    return ex * ex + ey * ey;
  };
  const double tolerance2 = tolerance_px * tolerance_px;
  std::vector<bool> keep(n, false);
  const auto finite = [&](std::size_t k) { return std::isfinite(s.x[k]) && std::isfinite(s.y[k]); };
  std::vector<std::pair<std::size_t, std::size_t>> pending;
  // Each finite run between gaps, cut into runs of kSimplifyRun points, simplified on its own
  // (Ramer-Douglas-Peucker); the gaps and every run's ends kept.
  std::size_t begin = 0;
  while (begin < n) {
    if (!finite(begin)) {
      keep[begin++] = true;
      continue;
    }
    std::size_t end = begin;
    while (end + 1 < n && end + 1 - begin < kSimplifyRun && finite(end + 1)) ++end;
    keep[begin] = keep[end] = true;
    pending.assign(1, {begin, end});
    while (!pending.empty()) {
      const auto [a, b] = pending.back();
      pending.pop_back();
      if (b <= a + 1) continue;
      std::size_t farthest = a + 1;
      double largest = -1.0;
      for (std::size_t k = a + 1; k < b; ++k) {
        const double d = distance2(k, a, b);
        if (d > largest) {
          largest = d;
          farthest = k;
        }
      }
      if (largest <= tolerance2) continue;
      keep[farthest] = true;
      pending.push_back({a, farthest});
      pending.push_back({farthest, b});
    }
    // A run cut at its length goes on from its last point (kept), so the drawn line is joined.
    begin = end > begin && end + 1 < n && finite(end + 1) ? end : end + 1;
  }
  std::vector<std::size_t> kept;
  for (std::size_t k = 0; k < n; ++k)
    if (keep[k]) kept.push_back(k);
  return kept;
}

void write_png_panels(const std::vector<PlotSpec>& panels, const std::filesystem::path& png) {
  write_png_figures({{panels, png}});
}

void write_png_figures(const std::vector<Figure>& figures) {
  if (figures.empty()) return;
  // Every file from one gnuplot, each into its partial file; renamed only when gnuplot is done.
  std::vector<std::filesystem::path> partial, final;
  std::string script;
  for (std::size_t f = 0; f < figures.size(); ++f) {
    const Figure& figure_spec = figures[f];
    if (figure_spec.panels.empty())
      throw std::invalid_argument("no panels to plot into " + figure_spec.png.string());
    std::filesystem::path svg = figure_spec.png;
    svg.replace_extension(".svg");
    std::string tag = "f";
    tag += std::to_string(f);
    for (const std::filesystem::path& file : {figure_spec.png, svg}) {
      final.push_back(file);
      partial.push_back(file.string() + ".partial");
    }
    script += figure_data(figure_spec.panels, tag) +
              figure(figure_spec.panels, tag, "pngcairo", partial[partial.size() - 2]) +
              figure(figure_spec.panels, tag, "svg dynamic", partial.back());
  }
  try {
    run_gnuplot_script(script, figures.front().png);
    for (std::size_t i = 0; i < partial.size(); ++i)
      if (!std::filesystem::exists(partial[i]) || std::filesystem::file_size(partial[i]) == 0)
        throw std::runtime_error("gnuplot wrote no figure into " + final[i].string());
    for (std::size_t i = 0; i < partial.size(); ++i) std::filesystem::rename(partial[i], final[i]);
  } catch (...) {
    for (const std::filesystem::path& file : partial) {
      std::error_code ignored;
      std::filesystem::remove(file, ignored);
    }
    throw;
  }
}

}  // namespace rths::util
