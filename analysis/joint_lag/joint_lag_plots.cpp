#include "analysis/joint_lag/joint_lag_plots.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "util/plot.h"
#include "util/plot_layout.h"

namespace rths::analysis {
namespace {

// Log colour scale (the error spans decades towards instability); zero error is drawn at this
// floor.
constexpr double kMapFloorPercent = 0.01;
constexpr int kMapWidth = 1200;  // px

// The map's data files beside the figures: the grid (blocks of equal round trip), the diverged
// points, the bounded points past the boundary, and the continuous boundary; all in ms and %.
// The map is printed across a page's width (util/plot_layout.h).
int map_font() { return util::figure_font_points(kMapWidth, true); }

struct MapFiles {
  std::filesystem::path grid, diverged, past, boundary, compensated_boundary;
};

void write_boundary(const std::vector<BoundaryPoint>& boundary, const std::filesystem::path& file) {
  std::ofstream out(file);
  out << "# critical_network_round_trip_ms actuator_lag_ms\n";
  for (const auto& b : boundary)
    if (b.critical_round_trip)
      out << *b.critical_round_trip * 1e3 << ' ' << b.actuator_lag * 1e3 << "\n";
}

bool has_crossing(const std::vector<BoundaryPoint>& boundary) {
  return std::any_of(boundary.begin(), boundary.end(),
                     [](const BoundaryPoint& b) { return b.critical_round_trip.has_value(); });
}

MapFiles write_map_data(const JointLagResult& result, const std::filesystem::path& out) {
  const MapFiles files{out / "error_map.dat", out / "error_map_diverged.dat",
                       out / "error_map_past_boundary.dat", out / "error_map_boundary.dat",
                       out / "error_map_compensated_boundary.dat"};
  {
    std::ofstream file(files.grid);
    file << "# network_round_trip_ms actuator_lag_ms rms_error_pct (blocks of equal round trip)\n";
    double previous = std::nan("");
    for (const auto& p : result.grid) {
      if (!std::isnan(previous) && p.network_round_trip != previous) file << "\n";
      previous = p.network_round_trip;
      file << p.network_round_trip * 1e3 << ' ' << p.actuator_lag * 1e3 << ' '
           << (p.diverged ? std::nan("") : std::max(p.rms_error_pct, kMapFloorPercent)) << "\n";
    }
  }
  {
    std::ofstream file(files.diverged);
    file << "# network_round_trip_ms actuator_lag_ms of diverged points\n";
    for (const auto& p : result.grid)
      if (p.diverged) file << p.network_round_trip * 1e3 << ' ' << p.actuator_lag * 1e3 << "\n";
  }
  {
    std::ofstream file(files.past);
    file << "# network_round_trip_ms actuator_lag_ms of bounded points past the stability "
            "boundary\n";
    for (const auto& p : result.grid)
      if (p.past_boundary && !p.diverged)
        file << p.network_round_trip * 1e3 << ' ' << p.actuator_lag * 1e3 << "\n";
  }
  write_boundary(result.boundary, files.boundary);
  if (!result.compensated_boundary.empty())
    write_boundary(result.compensated_boundary, files.compensated_boundary);
  return files;
}

// Contour levels of the map: the 1-2-5 series over the grid's bounded non-zero E_rms, from the
// largest step below its smallest value (a line inside the cells next to the lag-free corner,
// where the interpolation from zero would squeeze any lower one) to its largest value.
std::vector<double> contour_levels(const JointLagResult& result) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const auto& p : result.grid) {
    if (p.diverged || !(p.rms_error_pct > 0.0)) continue;
    lo = std::min(lo, p.rms_error_pct);
    hi = std::max(hi, p.rms_error_pct);
  }
  std::vector<double> levels;
  double below = 0.0;
  for (double decade = 1e-2; decade <= hi; decade *= 10.0)
    for (const double step : {1.0, 2.0, 5.0}) {
      const double level = decade * step;
      if (level < lo)
        below = level;
      else if (level <= hi)
        levels.push_back(level);
    }
  if (below > 0.0) levels.insert(levels.begin(), below);
  return levels;
}

// The point halfway along a contour piece (by length), and the piece's length.
std::pair<std::array<double, 3>, double> halfway(const std::vector<std::array<double, 3>>& piece) {
  std::vector<double> along(1, 0.0);
  for (std::size_t k = 1; k < piece.size(); ++k)
    along.push_back(along.back() +
                    std::hypot(piece[k][0] - piece[k - 1][0], piece[k][1] - piece[k - 1][1]));
  const double half = along.back() / 2.0;
  std::size_t k = 1;
  while (k + 1 < piece.size() && along[k] < half) ++k;
  const double span = along[k] - along[k - 1];
  const double f = span > 0.0 ? (half - along[k - 1]) / span : 0.0;
  std::array<double, 3> point = piece[k];
  for (int c = 0; c < 2; ++c) point[c] = piece[k - 1][c] + f * (piece[k][c] - piece[k - 1][c]);
  return {point, along.back()};
}

// The labels of the contour table gnuplot wrote (blocks of "x y level" lines; a level comes in
// pieces where the grid's corners or diverged cells cut it): halfway along every piece at least
// half as long as its level's longest, so each line drawn long enough to read carries its value
// and a short stub does not. "x y level" lines into `labels`.
void write_contour_labels(const std::filesystem::path& contours,
                          const std::filesystem::path& labels) {
  std::ifstream in(contours);
  std::vector<std::pair<std::array<double, 3>, double>> pieces;  // label point, length
  std::map<double, double> longest;                              // level: longest piece
  std::vector<std::array<double, 3>> piece;
  const auto close_piece = [&] {
    if (piece.size() >= 2) {
      pieces.push_back(halfway(piece));
      double& most = longest[piece.front()[2]];
      most = std::max(most, pieces.back().second);
    }
    piece.clear();
  };
  for (std::string line; std::getline(in, line);) {
    std::array<double, 3> point{};
    std::istringstream fields(line);
    if (line.empty() || line[0] == '#' || !(fields >> point[0] >> point[1] >> point[2])) {
      close_piece();
      continue;
    }
    piece.push_back(point);
  }
  close_piece();
  std::ofstream out(labels);
  out << "# network_round_trip_ms actuator_lag_ms rms_error_pct: a label per contour piece\n";
  for (const auto& [point, length] : pieces)
    if (length >= 0.5 * longest[point[2]])
      out << point[0] << ' ' << point[1] << ' ' << point[2] << "\n";
}

// The spacing of a grid axis (ms): its smallest gap between distinct values, 1 when it has one.
double cell_size(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  double gap = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < values.size(); ++i)
    if (values[i] > values[i - 1]) gap = std::min(gap, values[i] - values[i - 1]);
  return std::isfinite(gap) ? gap : 1.0;
}

// The map's settings: title, axes (each cell whole: the range reaches half a cell past the
// outer grid points), the log colour scale in a perceptually uniform palette, the legend below.
std::string map_settings(const JointLagResult& result) {
  std::vector<double> r, a;
  for (const auto& p : result.grid) {
    r.push_back(p.network_round_trip * 1e3);
    a.push_back(p.actuator_lag * 1e3);
  }
  const double dr = cell_size(r) / 2, da = cell_size(a) / 2;
  std::ostringstream out;
  out << "set bmargin 11\nset title \"Joint lag (" << result.study_name << ", actuator "
      << result.actuator_model << ")"
      << (result.compensated_boundary_note.empty() ? "" : ", every point with a force predictor")
      << "\\nE_rms of the displacement against the lag-free reference, %"
      << (!result.compensated_boundary_note.empty() && !has_crossing(result.compensated_boundary)
              ? "\\nwith the predictor: stable at every lag for its model's error"
              : "")
      << "\"\n"
      << "set xlabel 'network round trip (ms)'\nset ylabel 'actuator lag (ms)'\n"
      << "set cblabel 'E_rms (%), log scale'\nset logscale cb\nset format cb '%g'\n"
      << "set cbrange [" << kMapFloorPercent
      << ":*]\n"
      // viridis: perceptually uniform and readable in grey, unlike a rainbow.
      << "set palette defined (0 '#440154', 1 '#482878', 2 '#3E4A89', 3 '#31688E', 4 '#26828E', "
         "5 '#1F9E89', 6 '#35B779', 7 '#6DCD59', 8 '#B4DE2C', 9 '#FDE725')\n"
      << "set style textbox opaque fc rgb 'white' noborder\n"
      << "set xrange [" << *std::min_element(r.begin(), r.end()) - dr << ":"
      << *std::max_element(r.begin(), r.end()) + dr << "]\n"
      << "set yrange [" << *std::min_element(a.begin(), a.end()) - da << ":"
      << *std::max_element(a.begin(), a.end()) + da << "]\n"
      << "set key outside below center vertical maxrows 5 box width 2\n";
  return out.str();
}

// The plot command: cells, contour lines with one label each, the points past the boundary
// (open circles), the boundary itself, diverged points (crosses); only the layers that exist.
std::string map_plot(const JointLagResult& result, const MapFiles& files,
                     const std::filesystem::path& contours, const std::filesystem::path& labels) {
  const auto any = [&](auto&& predicate) {
    return std::any_of(result.grid.begin(), result.grid.end(), predicate);
  };
  std::string plot = "plot '" + files.grid.string() + "' using 1:2:3 with image pixels notitle";
  if (std::filesystem::file_size(contours) > 0)
    plot += ", '" + contours.string() +
            "' using 1:2 with lines lc rgb 'black' lw 1 title 'E_rms contours (%, labelled)', '" +
            labels.string() + "' using 1:2:(sprintf('%g %%', $3)) with labels boxed font 'sans," +
            std::to_string(map_font() - 1) +
            "' tc rgb 'black' "
            "notitle";
  if (any([](const JointLagPoint& p) { return p.past_boundary && !p.diverged; }))
    plot += ", '" + files.past.string() +
            "' using 1:2 with points pt 6 ps 3 lw 2 lc rgb 'black' title 'past the stability "
            "boundary, bounded in this record'";
  const bool compensated = !result.compensated_boundary_note.empty();
  if (has_crossing(result.boundary))
    plot += ", '" + files.boundary.string() +
            "' using 1:2 with lines lc rgb 'magenta' lw 4 dt 2 title 'stability boundary" +
            (compensated ? " without the predictor" : "") + " (continuous)'";
  if (has_crossing(result.compensated_boundary))
    plot += ", '" + files.compensated_boundary.string() +
            "' using 1:2 with lines lc rgb '#E66100' lw 4 title 'stability boundary with the "
            "predictor (its model frozen at its initial error)'";
  if (any([](const JointLagPoint& p) { return p.diverged; }))
    plot += ", '" + files.diverged.string() +
            "' using 1:2 with points pt 2 ps 3 lw 2 lc rgb 'black' title 'diverged (no colour: "
            "its error measures nothing)'";
  return plot;
}

// The 2-D heat map: E_rms % over (network round trip, actuator lag), labelled contour lines,
// the continuous stability boundary, the points past it and the diverged ones marked. PNG and
// SVG; the scripts are kept beside them, so the map can be redrawn or restyled by hand.
}  // namespace

void write_error_map(const JointLagResult& result, const std::filesystem::path& out) {
  const MapFiles files = write_map_data(result, out);
  const auto contours = out / "error_map_contours.dat", labels = out / "error_map_labels.dat";
  std::ostringstream table;
  table << "set table '" << contours.string() << "'\nunset surface\nset contour base\n";
  if (const std::vector<double> levels = contour_levels(result); !levels.empty()) {
    table << "set cntrparam levels discrete ";
    for (std::size_t i = 0; i < levels.size(); ++i) table << (i ? "," : "") << levels[i];
    table << "\nsplot '" << files.grid.string() << "' using 1:2:3 with lines notitle\n";
  }
  table << "unset table\n";
  std::ofstream(out / "error_map_contours.gp") << table.str();
  util::run_gnuplot_script(table.str(), contours);
  if (!std::filesystem::exists(contours)) std::ofstream{contours};
  write_contour_labels(contours, labels);
  std::ostringstream figure;
  figure << map_settings(result);
  const std::string plot = map_plot(result, files, contours, labels);
  for (const char* terminal : {"pngcairo size 1200,820", "svg size 1200,820 dynamic"}) {
    const bool png = std::string(terminal).rfind("png", 0) == 0;
    figure << "set terminal " << terminal << " noenhanced font 'sans," << map_font() << "'\n"
           << "set output '" << (out / (png ? "error_map.png" : "error_map.svg")).string() << "'\n"
           << plot << "\n";
  }
  std::ofstream(out / "error_map.gp") << figure.str();
  util::run_gnuplot_script(figure.str(), out / "error_map.png");
}

void write_total_lag_png(const JointLagResult& result, const std::filesystem::path& out) {
  util::PlotSpec spec;
  spec.title = "Measured total lag vs injected network + actuator lag";
  spec.xlabel = "injected network round trip + actuator lag (ms)";
  spec.ylabel = "measured total lag (ms)";
  util::Series emulated{"in-process grid (J1 of realised vs command)", {}, {}, "points pt 7"};
  util::Series identity{"measured = injected", {}, {}, "lines dt 2"};
  double largest = 0.0;
  for (const auto& p : result.grid) {
    if (p.diverged) continue;
    emulated.x.push_back((p.network_round_trip + p.actuator_lag) * 1e3);
    emulated.y.push_back(p.measured_total_lag * 1e3);
    largest = std::max({largest, emulated.x.back(), emulated.y.back()});
  }
  spec.series.push_back(emulated);
  if (!result.measured.empty()) {
    util::Series sites{"across sites (measured from the record)", {}, {}, "points pt 9 ps 2"};
    for (const auto& p : result.measured) {
      sites.x.push_back((p.network_round_trip + p.actuator_lag) * 1e3);
      sites.y.push_back(p.measured_total_lag * 1e3);
      largest = std::max({largest, sites.x.back(), sites.y.back()});
    }
    spec.series.push_back(sites);
  }
  identity.x = {0.0, largest};
  identity.y = {0.0, largest};
  spec.series.push_back(identity);
  util::write_png_plot(spec, out / "total_lag.png");
}

}  // namespace rths::analysis
