// The study's figures (analysis/study_run/study_run.h: study_plot_files, write_study_plots): the paper's
// Fig. 3, the force-displacement loops the integrator sees, the tracking of each actuator and,
// for a case with a force predictor, the force each predicted link measured against the
// predictor's model of it.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "analysis/study_run/response_envelope_plots.h"
#include "analysis/study_run/study_run.h"
#include "core/metrics.h"
#include "util/plot.h"

namespace rths::analysis {

std::vector<std::string> study_plot_files() {
  return {"displacement.png",       "displacement.svg",     "force_displacement.png",
          "force_displacement.svg", "tracking.png",         "tracking.svg",
          "force_prediction.png",   "force_prediction.svg", "response_envelope.png",
          "response_envelope.svg",  "floor_histories.png",  "floor_histories.svg"};
}

namespace {

// Start of the `window` seconds of the reference with the most energy (sum of u^2).
double strongest_window_start(const std::vector<double>& u, double dt, double window) {
  const std::size_t length =
      std::min(u.size(), static_cast<std::size_t>(std::llround(window / dt)));
  if (length == 0 || length >= u.size()) return 0.0;
  double energy = 0.0;
  for (std::size_t k = 0; k < length; ++k) energy += u[k] * u[k];
  double best = energy;
  std::size_t best_start = 0;
  for (std::size_t start = 1; start + length <= u.size(); ++start) {
    energy += u[start + length - 1] * u[start + length - 1] - u[start - 1] * u[start - 1];
    if (energy > best) {
      best = energy;
      best_start = start;
    }
  }
  return static_cast<double>(best_start) * dt;
}

// A case stopped before the record's end by a limit or its force predictor's bound (not diverged,
// which is labelled and clipped apart): its figures end at its stop and say so.
bool stopped_early(const CaseOutcome& c) { return !c.diverged() && c.status != "completed"; }

// "limit tripped at t = 5.114 s", the stop's cause and time; "" for a case that did not stop.
std::string stop_text(const CaseOutcome& c) {
  if (!stopped_early(c) || c.simulation.time.empty()) return "";
  char at[48];
  std::snprintf(at, sizeof at, " at t = %.4g s", c.simulation.time.back());
  return c.status + at;
}

// A dashed line where case c stopped, labelled with why (short: a label runs right of its line);
// nothing when it did not stop.
void mark_stop(util::PlotSpec& panel, const CaseOutcome& c) {
  if (stopped_early(c) && !c.simulation.time.empty())
    panel.markers.push_back({c.simulation.time.back(), c.status});
}

}  // namespace

namespace {

// " (within X mm of NAME)" when case i's response stays within 5 % of its peak of an earlier
// drawn case's, so that a reader told the curves overlap looks for both; else "".
std::string coincides_with(const std::vector<const CaseOutcome*>& drawn, std::size_t i) {
  const std::vector<double>& r = drawn[i]->response;
  const double peak = core::peak_abs(r);
  for (std::size_t j = 0; j < i; ++j) {
    const CaseOutcome& other = *drawn[j];
    if (other.diverged() || other.response.size() != r.size() || peak <= 0.0) continue;
    double largest = 0.0;
    for (std::size_t k = 0; k < r.size(); ++k)
      largest = std::max(largest, std::abs(r[k] - other.response[k]));
    if (largest > 0.05 * peak) continue;
    char within[64];
    std::snprintf(within, sizeof within, " (within %.2g mm of ", largest * 1e3);
    std::string text = within;
    text += other.name;
    text += ')';
    return text;
  }
  return "";
}

// The actuator the single-actuator figures draw: the config's first.
int first_actuator(const ActuatorNames& names) {
  return names.order.empty() ? 0 : names.order.front();
}

// force_displacement.png: what the integrator sees of the config's first actuator, one panel per case
// with the reference drawn over it, thin and dark. Without lag the reference's loop is a line
// that every lagged case's ellipse would cover on a shared panel, and cases with near-equal
// loops would cover each other. A diverged case has no loop worth drawing. No panel: no figure.
std::vector<util::PlotSpec> force_displacement_panels(const std::string& study,
                                                      const std::vector<const CaseOutcome*>& drawn,
                                                      const CaseOutcome& reference,
                                                      const ActuatorNames& names) {
  const int a = first_actuator(names);
  const auto has_loop = [a](const CaseOutcome& c) {
    return c.simulation.command.cols() > a && !c.diverged();
  };
  if (!has_loop(reference)) return {};
  const util::Series over = force_loop(reference, a, reference.name + " (drawn over)",
                                       "lines lc rgb '#222222' dt 1 lw 1.2");
  std::vector<util::PlotSpec> panels;
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    const CaseOutcome& c = *drawn[i];
    if (&c == &reference || !has_loop(c)) continue;
    util::PlotSpec panel{study + ": what the integrator sees at " + names.of(a) + ", " + c.name +
                             " against " + reference.name,
                         "commanded displacement (mm)", "measured force (kN)"};
    panel.series = {
        force_loop(c, a, c.name, "lines lc rgb '" + util::series_colour(i) + "' dt 1 lw 2"), over};
    panel.square = true;
    panels.push_back(std::move(panel));
  }
  // One scale on every panel, so that the loops compare at a glance.
  std::vector<util::Series> all, swapped;
  for (const util::PlotSpec& p : panels)
    for (const util::Series& s : p.series) {
      all.push_back(s);
      swapped.push_back({s.title, s.y, s.x});
    }
  const auto y = util::padded_y_range(all, {}, 0.04), x = util::padded_y_range(swapped, {}, 0.04);
  for (util::PlotSpec& p : panels) {
    if (y) std::tie(p.y_min, p.y_max) = *y;
    if (x) std::tie(p.x_min, p.x_max) = *x;
  }
  if (panels.empty()) {
    util::PlotSpec alone{study + ": what the integrator sees at " + names.of(a),
                         "commanded displacement (mm)", "measured force (kN)"};
    alone.series = {force_loop(reference, a, reference.name, "lines lw 2")};
    alone.square = true;
    panels.push_back(std::move(alone));
  }
  return panels;
}

// tracking.png, the RTHS benchmark's tracking figure: per case that drives an actuator and stayed
// bounded, x_t (the command of the config's first actuator) and x_m (what it measured there), mm,
// over the record, then beside it the same over `zoom` s from `zoom_start` (s), where the lag
// between them shows: a grid, a case a row. A
// case stopped early (a limit, its predictor's bound) is drawn up to its stop, marked there, and
// zoomed on its last `zoom` s when it stopped before the window's end (an empty window once made
// gnuplot fail every figure). No panel when no such case.
std::vector<util::PlotSpec> tracking_panels(const std::string& study,
                                            const std::vector<const CaseOutcome*>& drawn,
                                            const CaseOutcome& reference, double zoom_start,
                                            double zoom, const ActuatorNames& names) {
  std::vector<util::PlotSpec> panels;
  const int a = first_actuator(names);
  for (const CaseOutcome* c : drawn) {
    if (c == &reference || c->diverged() || c->simulation.command.cols() <= a ||
        c->simulation.realised.cols() <= a || c->simulation.time.size() < 2)
      continue;
    const std::string stop = stop_text(*c);
    util::PlotSpec whole{study + ": tracking of " + c->name + ", x_t (command) and x_m (measured)" +
                             (stop.empty() ? "" : ", " + stop),
                         "time (s)", "displacement at " + names.of(a) + " (mm)"};
    util::Series target{"x_t, command", c->simulation.time, {}, "lines lw 2"};
    util::Series measured{"x_m, measured", c->simulation.time, {}, "lines lw 1"};
    for (Eigen::Index k = 0; k < c->simulation.command.rows(); ++k) {
      target.y.push_back(c->simulation.command(k, a) * 1e3);
      measured.y.push_back(c->simulation.realised(k, a) * 1e3);
    }
    target.x.resize(target.y.size());
    measured.x.resize(measured.y.size());
    whole.series = {target, measured};
    mark_stop(whole, *c);
    util::PlotSpec close = whole;
    double start = zoom_start;
    if (!target.x.empty() && target.x.back() < start + zoom)
      start = std::max(0.0, target.x.back() - zoom);
    char title[200];
    std::snprintf(title, sizeof title, "zoom: %s over %g s %s", c->name.c_str(), zoom,
                  start == zoom_start ? "at the reference's strongest" : "up to its stop");
    close.title = title;
    close.x_min = start;
    close.x_max = start + zoom;
    // The zoom's y range follows what is in its window.
    double lo = 0.0, hi = 0.0;
    for (std::size_t k = 0; k < target.x.size(); ++k) {
      if (target.x[k] < start || target.x[k] > start + zoom) continue;
      lo = std::min({lo, target.y[k], measured.y[k]});
      hi = std::max({hi, target.y[k], measured.y[k]});
    }
    if (hi > lo) {
      close.y_min = lo - 0.08 * (hi - lo);
      close.y_max = hi + 0.08 * (hi - lo);
    }
    whole.height = close.height = 340;
    whole.columns = 2;
    panels.push_back(std::move(whole));
    panels.push_back(std::move(close));
  }
  return panels;
}

// force_prediction.png: per case with a force predictor (core/force_predictor.h) and per link it
// predicts (in config order, named by its site), the force f_m the link's answer measured (kN,
// as it arrived, the link's lag late) against the model's prediction of it at the displacement
// measured with it, f_m - e, and beside it the prediction error e = f_m - model (kN): a grid, a
// link a row. Where they part, the loop carries the model's error that late; a case stopped
// early ends at its stop, marked. No panel when no case has a predictor.
std::vector<util::PlotSpec> force_prediction_panels(const std::vector<const CaseOutcome*>& drawn,
                                                    const ActuatorNames& names) {
  std::vector<util::PlotSpec> panels;
  for (const CaseOutcome* c : drawn)
    for (const int a : names.order) {
      const core::SimulationResult& r = c->simulation;
      const auto& predicted = c->predicted_actuators;
      if (std::find(predicted.begin(), predicted.end(), a) == predicted.end() ||
          a >= r.measured_force.cols() || a >= r.prediction_error.cols())
        continue;
      const std::string link = names.of(a);
      const std::string stop = stop_text(*c);
      util::PlotSpec forces{c->name + ": force measured at " + link +
                                " and the predictor's model of it" +
                                (stop.empty() ? "" : ", " + stop),
                            "time (s)", "force (kN)"};
      util::Series measured{"measured (as it arrived)", r.time, {}, "lines lw 2"};
      util::Series model{"the model's prediction", r.time, {}, "lines lw 1"};
      util::PlotSpec error{c->name + ": prediction error at " + link + ", measured - model",
                           "time (s)", "error (kN)"};
      util::Series e{"prediction error", r.time, {}, "lines lw 1"};
      for (Eigen::Index k = 0; k < r.measured_force.rows(); ++k) {
        measured.y.push_back(r.measured_force(k, a) * 1e-3);
        model.y.push_back((r.measured_force(k, a) - r.prediction_error(k, a)) * 1e-3);
        e.y.push_back(r.prediction_error(k, a) * 1e-3);
      }
      for (util::Series* s : {&measured, &model, &e}) s->x.resize(s->y.size());
      forces.series = {measured, model};
      error.series = {e};
      mark_stop(forces, *c);
      mark_stop(error, *c);
      forces.height = error.height = 340;
      forces.columns = 2;
      panels.push_back(std::move(forces));
      panels.push_back(std::move(error));
    }
  return panels;
}

// The y axis of `spec` padded around the series `setting_axes` (indices), when any has a value.
void fit_y_axis(util::PlotSpec& spec, const std::vector<std::size_t>& setting_axes) {
  if (const auto range = util::padded_y_range(spec.series, setting_axes)) {
    std::tie(spec.y_min, spec.y_max) = *range;
  }
}

// displacement.png: every case's response (mm) over the record, its difference from the
// reference, and the strongest 5 s of the reference; the axes follow the cases that stayed
// bounded, so a diverged case does not flatten the others.
std::vector<util::PlotSpec> displacement_panels(const StudyOutcome& outcome,
                                                const std::vector<const CaseOutcome*>& drawn,
                                                const CaseOutcome& reference) {
  const std::string response = outcome.response.describe();
  util::PlotSpec displacement{outcome.study_name + ": " + response + " displacement, every case",
                              "time (s)",
                              "displacement (mm)",
                              {}};
  util::PlotSpec difference{"difference from the reference (" + reference.name + ")",
                            "time (s)",
                            "case - reference (mm)",
                            {}};
  std::vector<std::size_t> bounded, bounded_difference;  // series that set the axes
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    const CaseOutcome& c = *drawn[i];
    // A case a limit stopped ran away (|u| or |v| past the bound): clipped, as a diverged one.
    const bool clipped = c.diverged() || c.status == "limit tripped";
    const std::string label =
        c.name + (c.diverged()       ? " (" + c.status + ", clipped)"
                  : stopped_early(c) ? " (" + stop_text(c) + (clipped ? ", clipped)" : ")")
                                     : coincides_with(drawn, i));
    // Each case keeps its colour on every panel and is drawn thinner than the case before it, so
    // that two cases whose responses coincide are both seen (solid: cairo draws a dashed line of
    // 10^4 points very slowly).
    const std::string style = "lines lc rgb '" + util::series_colour(i) + "' dt 1 lw " +
                              std::to_string(std::max(0.7, 3.0 - 0.8 * static_cast<double>(i)));
    util::Series s{label, c.simulation.time, {}, style};
    for (double u : c.response) s.y.push_back(u * 1e3);
    if (!clipped) bounded.push_back(displacement.series.size());
    displacement.series.push_back(std::move(s));
    mark_stop(displacement, c);
    if (&c != &reference) {
      // The reference against itself is a zero line that says nothing: it is left out.
      util::Series d{label, c.simulation.time, {}, style};
      for (std::size_t k = 0; k < c.response.size() && k < reference.response.size(); ++k) {
        d.y.push_back((c.response[k] - reference.response[k]) * 1e3);
      }
      if (!clipped) bounded_difference.push_back(difference.series.size());
      difference.series.push_back(std::move(d));
    }
  }
  fit_y_axis(displacement, bounded);
  fit_y_axis(difference, bounded_difference);
  util::PlotSpec zoom = displacement;
  const double start = strongest_window_start(reference.response, reference.simulation.dt, 5.0);
  zoom.title = "zoom: the strongest 5 s of the reference";
  zoom.x_min = start;
  zoom.x_max = start + 5.0;
  std::vector<util::PlotSpec> panels = {displacement};
  if (!difference.series.empty()) panels.push_back(difference);
  panels.push_back(zoom);
  for (util::PlotSpec& p : panels) p.height = 380;
  return panels;
}

}  // namespace

std::vector<std::string> write_study_plots(const StudyOutcome& outcome,
                                           const std::filesystem::path& directory) {
  std::filesystem::create_directories(directory);
  const CaseOutcome& reference = outcome.reference();
  std::vector<const CaseOutcome*> drawn;  // the lag-free reference first, when it is not a case
  if (outcome.lag_free_reference) drawn.push_back(&*outcome.lag_free_reference);
  for (const CaseOutcome& c : outcome.cases) drawn.push_back(&c);
  const std::vector<util::PlotSpec> panels = displacement_panels(outcome, drawn, reference);
  // A stale figure must not stay beside a study that has none of its kind.
  std::filesystem::remove(directory / "force_displacement.png");
  std::filesystem::remove(directory / "force_displacement.svg");
  std::filesystem::remove(directory / "tracking.png");
  std::filesystem::remove(directory / "tracking.svg");
  std::filesystem::remove(directory / "force_prediction.png");
  std::filesystem::remove(directory / "force_prediction.svg");
  remove_many_dof_figures(directory);
  // One gnuplot draws the three figures: its start-up costs more than a decimated figure.
  std::vector<util::Figure> figures = {{panels, directory / "displacement.png"}};
  if (auto loops =
          force_displacement_panels(outcome.study_name, drawn, reference, outcome.actuators);
      !loops.empty())
    figures.push_back({std::move(loops), directory / "force_displacement.png"});
  const double tracking_start =
      strongest_window_start(reference.response, reference.simulation.dt, 1.0);
  if (auto tracking = tracking_panels(outcome.study_name, drawn, reference, tracking_start, 1.0,
                                      outcome.actuators);
      !tracking.empty())
    figures.push_back({std::move(tracking), directory / "tracking.png"});
  if (auto predicted = force_prediction_panels(drawn, outcome.actuators); !predicted.empty())
    figures.push_back({std::move(predicted), directory / "force_prediction.png"});
  for (util::Figure& figure : many_dof_figures(outcome, drawn, directory))
    figures.push_back(std::move(figure));
  util::write_png_figures(figures);
  std::vector<std::string> written;
  for (const util::Figure& f : figures) written.push_back(f.png.filename().string());
  return written;
}

}  // namespace rths::analysis
