#include "analysis/sweep/sweep_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "analysis/sweep/sweep_internal.h"
#include "core/metrics.h"
#include "core/time_text.h"
#include "util/plot.h"

namespace rths::analysis {
namespace {

using sweep_internal::format_number;

// Series key: everything but period and stiffness.
using SeriesKey = std::tuple<std::string, double, double, std::string,
                             double>;  // model, alpha, dt, motion, delay

SeriesKey series_key(const SweepTableRow& r) { return {r.model, r.alpha, r.dt, r.motion, r.delay}; }

// What varies across the rows, so a label names only what tells curves apart, and each delay and
// model keeps one colour and one dash on every figure.
struct SweepAxes {
  double stiffness = 0;  // the first (smallest) stiffness: the others coincide
  std::vector<std::string> models, motions;
  std::vector<double> alphas, dts, delays;

  explicit SweepAxes(const std::vector<SweepTableRow>& rows) {
    std::set<std::string> model_set, motion_set;
    std::set<double> alpha_set, dt_set, delay_set;
    stiffness = rows.front().stiffness;
    for (const auto& r : rows) {
      stiffness = std::min(stiffness, r.stiffness);
      model_set.insert(r.model);
      motion_set.insert(r.motion);
      alpha_set.insert(r.alpha);
      dt_set.insert(r.dt);
      if (r.delay > 0) delay_set.insert(r.delay);
    }
    models.assign(model_set.begin(), model_set.end());
    motions.assign(motion_set.begin(), motion_set.end());
    alphas.assign(alpha_set.begin(), alpha_set.end());
    dts.assign(dt_set.begin(), dt_set.end());
    delays.assign(delay_set.begin(), delay_set.end());
  }

  template <class T>
  static int index_of(const std::vector<T>& values, const T& value) {
    return static_cast<int>(std::find(values.begin(), values.end(), value) - values.begin());
  }
  // Colour by delay, dash and point type by model.
  std::string style(double delay, const std::string& model, const std::string& with) const {
    const int m = index_of(models, model);
    return with + " lc rgb '" +
           util::series_colour(static_cast<std::size_t>(index_of(delays, delay))) + "' dt " +
           std::to_string(m % 4 + 1) + " pt " + std::to_string(m % 6 + 5);
  }
  std::string label(const SeriesKey& key) const {
    const auto& [model, alpha, dt, motion, delay] = key;
    std::string text = "delay " + core::format_ms(delay, 4);
    if (models.size() > 1) text += ", " + model_label(model);
    if (alphas.size() > 1) text += ", alpha " + format_number(alpha);
    if (dts.size() > 1) text += ", dt " + format_number(dt * 1e3) + " ms";
    if (motions.size() > 1) text += ", " + motion;
    return text;
  }
};

// One error measure of a row, as a figure names it.
struct Measure {
  const char* title;  // "E_rms = 100 sqrt(sum e^2 / sum u_ref^2)"
  const char* axis;   // "E_rms (%, log)"
  double SweepTableRow::*value;
};
const Measure kErms{"E_rms = 100 sqrt(sum e^2 / sum u_ref^2)", "E_rms (%, log)",
                    &SweepTableRow::rms_error_pct};
const Measure kPaperNrmse{"the paper's Fig. 4: NRMSE = 100 sqrt(mean e^2) / median|u_ref|",
                          "NRMSE (%, log)", &SweepTableRow::nrmse_pct};
const Measure kPaperEq2{"the paper's Eq. 2 as printed (depends on N)", "Eq. 2 (log)",
                        &SweepTableRow::eq2_paper};

// The rows at the figure's stiffness with a delay, one curve sorted by period per series key.
std::map<SeriesKey, std::vector<const SweepTableRow*>> curves_by_key(
    const std::vector<SweepTableRow>& rows, double stiffness) {
  std::map<SeriesKey, std::vector<const SweepTableRow*>> curves;
  for (const auto& r : rows) {
    if (r.stiffness != stiffness || !(r.delay > 0)) continue;
    curves[series_key(r)].push_back(&r);
  }
  for (auto& [key, points] : curves)
    std::sort(points.begin(), points.end(),
              [](const SweepTableRow* l, const SweepTableRow* r) { return l->period < r->period; });
  return curves;
}

// Smallest and largest bounded value > 0 of a measure; {inf, 0} when there is none.
std::pair<double, double> bounded_range(
    const std::map<SeriesKey, std::vector<const SweepTableRow*>>& curves, const Measure& measure) {
  double smallest = std::numeric_limits<double>::infinity(), largest = 0.0;
  for (const auto& [key, points] : curves)
    for (const SweepTableRow* p : points) {
      const double value = p->*measure.value;
      if (!p->diverged && std::isfinite(value) && value > 0) {
        smallest = std::min(smallest, value);
        largest = std::max(largest, value);
      }
    }
  return {smallest, largest};
}

constexpr double kRowStep = 1.35;  // each curve's diverged marks sit this factor above the last's

// At most kPeriodsDrawn periods, spread over the swept range.
std::vector<double> periods_drawn(const std::vector<SweepTableRow>& rows) {
  constexpr std::size_t kPeriodsDrawn = 6;
  std::set<double> periods;
  for (const auto& r : rows) periods.insert(r.period);
  const std::vector<double> all(periods.begin(), periods.end());
  std::vector<double> drawn;
  for (std::size_t i = 0; i < std::min(kPeriodsDrawn, all.size()); ++i)
    drawn.push_back(
        all[all.size() <= kPeriodsDrawn ? i : i * (all.size() - 1) / (kPeriodsDrawn - 1)]);
  return drawn;
}

// The critical delay of each drawn period as a marker, those beyond the x range left out and
// the title saying so.
void mark_critical_delays(util::PlotSpec& plot, const std::vector<double>& periods,
                          const SweepTableRow& at, const CriticalDelayOf& critical_delay) {
  if (!critical_delay) return;
  for (double period : periods) {
    if (const auto critical = critical_delay(period, at.alpha, at.dt)) {
      plot.markers.push_back({*critical * 1e3, fmt::format("critical, T = {:.3g} s: {}", period,
                                                           core::format_ms(*critical))});
    }
  }
  const std::size_t before = plot.markers.size();
  std::erase_if(plot.markers, [&](const util::VerticalMarker& m) { return m.x > *plot.x_max; });
  if (plot.markers.size() < before)
    plot.title += " (critical delays beyond the swept range not drawn)";
}

// E_rms against delay, one curve per drawn period and model (colour by period, dash by model), at
// the first fraction, dt and record; diverged points on a row above the curves.
void write_sweep_delay_plot(const std::vector<SweepTableRow>& rows,
                            const std::filesystem::path& png, const std::string& title,
                            const CriticalDelayOf& critical_delay, const SweepAxes& axes,
                            const util::PlotSpec& by_period) {
  const SweepTableRow& first = rows.front();
  const std::vector<double> periods = periods_drawn(rows);
  util::PlotSpec plot{title + ": E_rms against delay, one curve per period" +
                          (axes.models.size() > 1 ? " and model" : ""),
                      "delay (ms)",
                      kErms.axis,
                      {},
                      true};
  plot.y_min = by_period.y_min;
  plot.y_max = by_period.y_max;
  plot.y_format = "%g";
  const double row = by_period.y_max ? *by_period.y_max / 1.5 / kRowStep : 1.0;
  util::Series diverged{
      "diverged (marked above the curves)", {}, {}, "points pt 2 ps 1.6 lw 2 lc rgb 'black'"};
  double largest_delay = 0.0;
  for (std::size_t p = 0; p < periods.size(); ++p) {
    for (std::size_t m = 0; m < axes.models.size(); ++m) {
      std::vector<const SweepTableRow*> points;
      for (const auto& r : rows)
        if (r.period == periods[p] && r.stiffness == axes.stiffness && r.model == axes.models[m] &&
            r.alpha == first.alpha && r.dt == first.dt && r.motion == first.motion && r.delay > 0)
          points.push_back(&r);
      if (points.empty()) continue;
      std::sort(points.begin(), points.end(), [](auto* l, auto* r) { return l->delay < r->delay; });
      std::string label = fmt::format("T = {:g} s", periods[p]);
      if (axes.models.size() > 1) label += ", " + model_label(axes.models[m]);
      util::Series curve{label,
                         {},
                         {},
                         "linespoints lc rgb '" + util::series_colour(p) + "' dt " +
                             std::to_string(m % 4 + 1) + " pt " + std::to_string(m % 6 + 5)};
      for (const SweepTableRow* r : points) {
        curve.x.push_back(r->delay * 1e3);
        curve.y.push_back(r->diverged ? std::nan("") : r->*kErms.value);
        largest_delay = std::max(largest_delay, r->delay);
        if (r->diverged) {
          diverged.x.push_back(r->delay * 1e3);
          diverged.y.push_back(row);
        }
      }
      plot.series.push_back(std::move(curve));
    }
  }
  if (plot.series.empty()) return;
  if (!diverged.x.empty()) plot.series.push_back(std::move(diverged));
  plot.x_min = 0.0;
  plot.x_max = largest_delay * 1e3 * 1.15;
  mark_critical_delays(plot, periods, first, critical_delay);
  util::write_png_plot(plot, png);
}

// One measure against period on a log axis, one curve per series key; each curve's diverged
// points on a row of its own above every bounded value, so they are seen but set no scale.
util::PlotSpec period_panel(const std::map<SeriesKey, std::vector<const SweepTableRow*>>& curves,
                            const SweepAxes& axes, const std::string& title,
                            const Measure& measure) {
  util::PlotSpec panel{title + ": " + measure.title, "period T (s)", measure.axis, {}, true};
  panel.height = 420;
  panel.y_format = "%g";
  const auto [smallest, largest] = bounded_range(curves, measure);
  const double first_row = largest > 0 ? largest * 3.0 : 1.0;
  std::vector<util::Series> marks;
  for (const auto& [key, points] : curves) {
    const std::string label = axes.label(key);
    util::Series curve{
        label, {}, {}, axes.style(std::get<4>(key), std::get<0>(key), "linespoints")};
    // One legend entry speaks for every curve's diverged points (each in its curve's colour and
    // point type): an entry per curve doubled a legend that already names every curve.
    util::Series diverged{
        marks.empty() ? "diverged: above the curves, in its curve's colour" : "",
        {},
        {},
        axes.style(std::get<4>(key), std::get<0>(key), "points") + " lw 2 ps 1.6"};
    const double row = first_row * std::pow(kRowStep, static_cast<double>(marks.size()));
    for (const SweepTableRow* p : points) {
      curve.x.push_back(p->period);
      curve.y.push_back(p->diverged ? std::nan("") : p->*measure.value);
      if (p->diverged) {
        diverged.x.push_back(p->period);
        diverged.y.push_back(row);
      }
    }
    panel.series.push_back(std::move(curve));
    if (!diverged.x.empty()) marks.push_back(std::move(diverged));
  }
  if (largest > 0) {
    panel.y_min = smallest / 2.0;
    panel.y_max = first_row * std::pow(kRowStep, static_cast<double>(marks.size())) * 1.5;
  }
  for (util::Series& m : marks) panel.series.push_back(std::move(m));
  return panel;
}

}  // namespace

std::string model_label(const std::string& model) {
  std::istringstream parts(model);
  std::string name, part, out;
  std::getline(parts, name, ':');
  while (std::getline(parts, part, ':')) {
    const auto equals = part.find('=');
    if (equals == std::string::npos) continue;
    const std::string key = part.substr(0, equals), value = part.substr(equals + 1);
    std::string shown = value;
    if (key == "uy") {
      shown = fmt::format("{:g} mm", std::stod(value) * 1e3);
    }
    out += (out.empty() ? "" : ", ") + key + " = " + shown;
  }
  return out.empty() ? name : name + " (" + out + ")";
}

std::filesystem::path sweep_delay_plot_path(const std::filesystem::path& png) {
  std::filesystem::path out = png;
  out.replace_filename(png.stem().string() + "_vs_delay" + png.extension().string());
  return out;
}

void write_sweep_plot(const std::vector<SweepTableRow>& rows, const std::filesystem::path& png,
                      const std::string& title, const CriticalDelayOf& critical_delay) {
  if (rows.empty()) throw std::invalid_argument("sweep plot: no rows");
  const SweepAxes axes(rows);
  const auto curves = curves_by_key(rows, axes.stiffness);
  if (curves.empty()) throw std::invalid_argument("sweep plot: no delay > 0 in the rows");
  std::vector<util::PlotSpec> panels;
  for (const Measure* measure : {&kErms, &kPaperNrmse, &kPaperEq2})
    panels.push_back(period_panel(curves, axes, title, *measure));
  util::write_png_panels(panels, png);
  write_sweep_delay_plot(rows, sweep_delay_plot_path(png), title, critical_delay, axes,
                         panels.front());
}

SweepTrends measure_trends(const std::vector<SweepTableRow>& rows, SweepMeasure measure) {
  const double SweepTableRow::*value =
      measure == SweepMeasure::kErms ? &SweepTableRow::rms_error_pct : &SweepTableRow::nrmse_pct;
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
    by_point[{series_key(r), r.period}].push_back(r.*value);
    by_series[{series_key(r), r.stiffness}].push_back({r.period, r.*value});
  }
  for (const auto& [key, values] : by_point) {
    if (values.size() < 2) continue;
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    const double scale = std::max(std::abs(*lo), std::abs(*hi));
    if (scale > 0)
      trends.stiffness_max_relative_difference =
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
      linear[{r.alpha, r.dt, r.motion, r.delay, r.period, r.stiffness}] = r.*value;
    }
  }
  std::vector<double> ratios;
  for (const auto& r : rows) {
    if (r.model == "linear" || r.diverged || !(r.delay > 0)) continue;
    const auto it = linear.find({r.alpha, r.dt, r.motion, r.delay, r.period, r.stiffness});
    if (it != linear.end() && it->second > 0) ratios.push_back(r.*value / it->second);
  }
  trends.nonlinear_to_linear_median_ratio =
      ratios.empty() ? std::nan("") : core::median(std::move(ratios));
  return trends;
}

nlohmann::json sweep_trends_json(const std::vector<SweepTableRow>& rows) {
  const auto number = [](double x) {
    return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json();
  };
  const auto measured = [&](SweepMeasure measure, const std::string& name) {
    const SweepTrends t = measure_trends(rows, measure);
    return nlohmann::json{
        {"measure", name},
        {"stiffness_max_relative_difference", number(t.stiffness_max_relative_difference)},
        {"period_falling_pair_fraction", number(t.period_falling_fraction)},
        {"nonlinear_to_linear_median_ratio", number(t.nonlinear_to_linear_median_ratio)},
        {"diverged_points", t.diverged_points}};
  };
  return {{"trends", measured(SweepMeasure::kErms, "E_rms (%)")},
          {"paper_trends", measured(SweepMeasure::kPaperNrmse,
                                    "NRMSE (%), the paper's median normalisation (its Fig. 4)")}};
}

}  // namespace rths::analysis
