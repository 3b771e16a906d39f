#include "analysis/sweep_report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "analysis/sweep_internal.h"
#include "core/metrics.h"
#include "util/plot.h"

namespace rths::analysis {
namespace {

using sweep_internal::format_number;

// Series key: everything but period and stiffness.
using SeriesKey = std::tuple<std::string, double, double, std::string, double>;  // model, alpha, dt, motion, delay

SeriesKey series_key(const SweepTableRow& r) { return {r.model, r.alpha, r.dt, r.motion, r.delay}; }

std::string delay_label(double delay) {
  std::ostringstream s;
  s.precision(4);
  s << "delay " << delay * 1e3 << " ms";
  return s.str();
}

}  // namespace

std::filesystem::path sweep_delay_plot_path(const std::filesystem::path& png) {
  std::filesystem::path out = png;
  out.replace_filename(png.stem().string() + "_vs_delay" + png.extension().string());
  return out;
}

void write_sweep_plot(const std::vector<SweepTableRow>& rows, const std::filesystem::path& png,
                      const std::string& title, const CriticalDelayOf& critical_delay) {
  if (rows.empty()) throw std::invalid_argument("sweep plot: no rows");
  double stiffness = rows.front().stiffness;
  std::set<std::string> models, motions;
  std::set<double> alphas, dts;
  for (const auto& r : rows) {
    stiffness = std::min(stiffness, r.stiffness);
    models.insert(r.model);
    motions.insert(r.motion);
    alphas.insert(r.alpha);
    dts.insert(r.dt);
  }
  struct Point {
    double period, nrmse_pct, eq2;
    bool diverged;
  };
  std::map<SeriesKey, std::vector<Point>> series;
  double largest = 0.0, smallest = std::numeric_limits<double>::infinity();
  for (const auto& r : rows) {
    if (r.stiffness != stiffness || !(r.delay > 0)) continue;
    series[series_key(r)].push_back({r.period, r.nrmse_pct, r.eq2_paper, r.diverged});
    if (!r.diverged && std::isfinite(r.nrmse_pct) && r.nrmse_pct > 0) {
      largest = std::max(largest, r.nrmse_pct);
      smallest = std::min(smallest, r.nrmse_pct);
    }
  }
  const std::string& name = title;
  util::PlotSpec nrmse_panel{name + ": NRMSE = 100 sqrt(mean e^2) / median|u_ref| (the paper's Fig. 4)",
                       "period T (s)", "NRMSE (%, log)", {}, true};
  util::PlotSpec eq2_panel{name + ": the paper's Eq. 2 as printed (depends on N)", "period T (s)",
                     "Eq. 2 (log)", {}, true};
  nrmse_panel.height = eq2_panel.height = 500;
  // Diverged points sit on a row above every bounded value, so they are seen but set no scale.
  const double diverged_row = largest > 0 ? largest * 3.0 : 1.0;
  if (largest > 0) {
    nrmse_panel.y_min = smallest / 2.0;
    nrmse_panel.y_max = diverged_row * 2.0;
  }
  util::Series diverged{"diverged (marked above the curves)", {}, {}, "points pt 2 ps 1.6 lw 2"};
  auto label_of = [&](const SeriesKey& key) {
    const auto& [model, alpha, dt, motion, delay] = key;
    std::string label = delay_label(delay);
    if (models.size() > 1) label += " " + model;
    if (alphas.size() > 1) label += " alpha=" + format_number(alpha);
    if (dts.size() > 1) label += " dt=" + format_number(dt);
    if (motions.size() > 1) label += " " + motion;
    return label;
  };
  for (auto& [key, points] : series) {
    std::sort(points.begin(), points.end(), [](const Point& l, const Point& r) { return l.period < r.period; });
    const std::string label = label_of(key);
    util::Series a{label, {}, {}, "linespoints"}, b{label, {}, {}, "linespoints"};
    for (const Point& p : points) {
      a.x.push_back(p.period);
      a.y.push_back(p.diverged ? std::nan("") : p.nrmse_pct);
      b.x.push_back(p.period);
      b.y.push_back(p.diverged ? std::nan("") : p.eq2);
      if (p.diverged) {
        diverged.x.push_back(p.period);
        diverged.y.push_back(diverged_row);
      }
    }
    nrmse_panel.series.push_back(std::move(a));
    eq2_panel.series.push_back(std::move(b));
  }
  if (nrmse_panel.series.empty()) throw std::invalid_argument("sweep plot: no delay > 0 in the rows");
  if (!diverged.x.empty()) nrmse_panel.series.push_back(std::move(diverged));
  util::write_png_panels({nrmse_panel, eq2_panel}, png);

  // Error against delay, one curve per period (at most kPeriodsDrawn, spread over the range), at
  // the first model, fraction, dt and record; the critical delay of each period drawn.
  constexpr std::size_t kPeriodsDrawn = 6;
  std::set<double> periods;
  for (const auto& r : rows) periods.insert(r.period);
  std::vector<double> all(periods.begin(), periods.end()), drawn;
  for (std::size_t i = 0; i < std::min(kPeriodsDrawn, all.size()); ++i) {
    const std::size_t at = all.size() <= kPeriodsDrawn ? i : i * (all.size() - 1) / (kPeriodsDrawn - 1);
    drawn.push_back(all[at]);
  }
  const SweepTableRow& first = rows.front();
  util::PlotSpec by_delay{name + ": NRMSE against delay, one curve per period", "delay (ms)", "NRMSE (%, log)", {}, true};
  if (largest > 0) {
    by_delay.y_min = nrmse_panel.y_min;
    by_delay.y_max = nrmse_panel.y_max;
  }
  util::Series diverged_by_delay{"diverged (marked above the curves)", {}, {}, "points pt 2 ps 1.6 lw 2"};
  double largest_delay = 0.0;
  for (double period : drawn) {
    std::vector<std::pair<double, const SweepTableRow*>> points;
    for (const auto& r : rows) {
      if (r.period == period && r.stiffness == stiffness && r.model == first.model && r.alpha == first.alpha &&
          r.dt == first.dt && r.motion == first.motion && r.delay > 0) {
        points.push_back({r.delay, &r});
        largest_delay = std::max(largest_delay, r.delay);
      }
    }
    std::sort(points.begin(), points.end());
    std::ostringstream label;
    label << "T = " << period << " s";
    util::Series curve{label.str(), {}, {}, "linespoints"};
    for (const auto& [delay, row] : points) {
      curve.x.push_back(delay * 1e3);
      curve.y.push_back(row->diverged ? std::nan("") : row->nrmse_pct);
      if (row->diverged) {
        diverged_by_delay.x.push_back(delay * 1e3);
        diverged_by_delay.y.push_back(diverged_row);
      }
    }
    if (curve.x.empty()) continue;
    if (critical_delay) {
      if (const auto critical = critical_delay(period, first.alpha, first.dt)) {
        std::ostringstream text;
        text.precision(3);
        text << "critical, T = " << period << " s: " << *critical * 1e3 << " ms";
        by_delay.markers.push_back({*critical * 1e3, text.str()});
      }
    }
    by_delay.series.push_back(std::move(curve));
  }
  if (!diverged_by_delay.x.empty()) by_delay.series.push_back(std::move(diverged_by_delay));
  by_delay.x_min = 0.0;
  by_delay.x_max = largest_delay * 1e3 * 1.15;
  // Critical delays beyond the swept range would squeeze the curves: drop them, say so in the title.
  const std::size_t before = by_delay.markers.size();
  std::erase_if(by_delay.markers, [&](const util::VerticalMarker& m) { return m.x > *by_delay.x_max; });
  if (by_delay.markers.size() < before) by_delay.title += " (critical delays beyond the swept range not drawn)";
  if (!by_delay.series.empty()) util::write_png_plot(by_delay, sweep_delay_plot_path(png));
}

SweepTrends measure_trends(const std::vector<SweepTableRow>& rows) {
  SweepTrends trends;
  // Stiffness: same point but stiffness.
  std::map<std::tuple<SeriesKey, double>, std::vector<double>> by_point;
  std::map<std::tuple<SeriesKey, double>, std::vector<std::pair<double, double>>> by_series;
  for (const auto& r : rows) {
    if (r.diverged) {
      ++trends.diverged_points;
      continue;
    }
    if (!(r.delay > 0)) continue;  // a zero delay leaves only round-off to compare
    by_point[{series_key(r), r.period}].push_back(r.nrmse_pct);
    by_series[{series_key(r), r.stiffness}].push_back({r.period, r.nrmse_pct});
  }
  for (const auto& [key, values] : by_point) {
    if (values.size() < 2) continue;
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    const double scale = std::max(std::abs(*lo), std::abs(*hi));
    if (scale > 0) trends.stiffness_max_relative_difference =
        std::max(trends.stiffness_max_relative_difference, (*hi - *lo) / scale);
  }
  std::size_t pairs = 0, falling = 0;
  for (auto& [key, points] : by_series) {
    std::sort(points.begin(), points.end());
    for (std::size_t i = 1; i < points.size(); ++i) {
      ++pairs;
      if (points[i].second < points[i - 1].second) ++falling;
    }
  }
  trends.period_falling_fraction = pairs ? static_cast<double>(falling) / pairs : std::nan("");
  std::map<std::tuple<double, double, std::string, double, double, double>, double> linear;
  for (const auto& r : rows) {
    if (r.model == "linear" && !r.diverged && r.delay > 0) {
      linear[{r.alpha, r.dt, r.motion, r.delay, r.period, r.stiffness}] = r.nrmse_pct;
    }
  }
  std::vector<double> ratios;
  for (const auto& r : rows) {
    if (r.model == "linear" || r.diverged || !(r.delay > 0)) continue;
    const auto it = linear.find({r.alpha, r.dt, r.motion, r.delay, r.period, r.stiffness});
    if (it != linear.end() && it->second > 0) ratios.push_back(r.nrmse_pct / it->second);
  }
  trends.nonlinear_to_linear_median_ratio = ratios.empty() ? std::nan("") : core::median(std::move(ratios));
  return trends;
}

}  // namespace rths::analysis
