#include "analysis/study_run/response_envelope_plots.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <regex>

namespace rths::analysis {

std::vector<int> recorded_floors(const core::SimulationResult& run) {
  if (!run.dofs.empty()) return run.dofs;
  std::vector<int> every(static_cast<std::size_t>(run.displacement.cols()));
  std::iota(every.begin(), every.end(), 0);
  return every;
}

std::vector<int> chosen_floors(const std::vector<int>& recorded) {
  if (recorded.size() <= static_cast<std::size_t>(kHistoryFloors)) return recorded;
  std::vector<int> chosen;
  const double last = static_cast<double>(recorded.size() - 1);
  for (int j = 0; j < kHistoryFloors; ++j)
    chosen.push_back(
        recorded[static_cast<std::size_t>(std::lround(last * j / (kHistoryFloors - 1)))]);
  return chosen;
}

util::Series force_loop(const CaseOutcome& c, int a, const std::string& label,
                        const std::string& style) {
  util::Series loop{label, {}, {}, style};
  for (Eigen::Index k = 0; k < c.simulation.command.rows(); ++k) {
    loop.x.push_back(c.simulation.command(k, a) * 1e3);
    loop.y.push_back(c.simulation.measured_force(k, a) * 1e-3);
  }
  return loop;
}

util::Series peak_over_height(const CaseOutcome& c, const std::vector<int>& floors, bool drift,
                              const std::string& label, const std::string& style) {
  util::Series profile{label, {}, {}, style};
  if (!drift) {
    profile.x.push_back(0.0);
    profile.y.push_back(0.0);
  }
  const core::Mat& u = c.simulation.displacement;
  Eigen::Index below_column = -1;
  int below = -1;
  for (int dof : floors) {
    const Eigen::Index column = c.simulation.column_of_dof(dof);
    if (column < 0) continue;
    double peak = 0.0;
    if (!drift) {
      peak = u.col(column).cwiseAbs().maxCoeff();
    } else {
      const core::Vec relative = below_column < 0 ? core::Vec(u.col(column))
                                                  : core::Vec(u.col(column) - u.col(below_column));
      peak = relative.cwiseAbs().maxCoeff() / static_cast<double>(dof - below);
    }
    profile.x.push_back(peak * 1e3);
    profile.y.push_back(static_cast<double>(dof + 1));
    below_column = column;
    below = dof;
  }
  return profile;
}

namespace {

constexpr const char* kReferenceStyle = "lines lc rgb '#222222' dt 1 lw 1.2";

bool bounded(const CaseOutcome& c) { return !c.diverged() && c.simulation.steps() > 0; }

// Case i's line in its colour (solid: cairo draws long dashed lines slowly), with `extra` options.
std::string case_style(std::size_t i, const std::string& kind = "lines",
                       const std::string& extra = "lw 2") {
  return kind + " lc rgb '" + util::series_colour(i) + "' dt 1 " + extra;
}

// Whether the recorded floors skip any: the drift is then averaged over the storeys between.
bool floors_skip(const std::vector<int>& floors) {
  for (std::size_t i = 0; i < floors.size(); ++i)
    if (floors[i] != static_cast<int>(i)) return true;
  return false;
}

// response_envelope.png's two panels.
std::vector<util::PlotSpec> envelope_panels(const StudyOutcome& outcome,
                                            const std::vector<const CaseOutcome*>& drawn,
                                            const std::vector<int>& floors) {
  const CaseOutcome& reference = outcome.reference();
  const bool averaged = floors_skip(floors);
  util::PlotSpec peak{outcome.study_name + ": peak displacement over height", "peak |u| (mm)",
                      "floor (DOF number)"};
  util::PlotSpec drift{averaged ? "peak storey drift, averaged between recorded floors"
                                : "peak inter-storey drift over height",
                       averaged ? "peak drift per storey (mm)" : "peak inter-storey drift (mm)",
                       "floor (DOF number)"};
  bool left_out = false;
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    const CaseOutcome& c = *drawn[i];
    if (&c == &reference) continue;
    if (!bounded(c)) {
      left_out = true;
      continue;
    }
    const std::string style = case_style(i, "linespoints", "lw 2 pt 7 ps 0.8");
    peak.series.push_back(peak_over_height(c, floors, false, c.name, style));
    drift.series.push_back(peak_over_height(c, floors, true, c.name, style));
  }
  const std::string over = "reference: " + reference.name + " (drawn over)";
  peak.series.push_back(peak_over_height(reference, floors, false, over, kReferenceStyle));
  drift.series.push_back(peak_over_height(reference, floors, true, over, kReferenceStyle));
  if (left_out) peak.title += " (diverged cases left out)";
  for (util::PlotSpec* p : {&peak, &drift}) {
    p->width = 800;
    p->height = 900;
    p->columns = 2;
    p->y_min = 0.0;
    p->y_max = static_cast<double>(floors.back() + 1) * 1.04;
  }
  return {peak, drift};
}

// floor_histories.png's panels: a chosen floor a panel.
std::vector<util::PlotSpec> history_panels(const StudyOutcome& outcome,
                                           const std::vector<const CaseOutcome*>& drawn,
                                           const std::vector<int>& floors) {
  const CaseOutcome& reference = outcome.reference();
  std::vector<util::PlotSpec> panels;
  for (int dof : chosen_floors(floors)) {
    const std::string number = std::to_string(dof + 1);
    util::PlotSpec panel{
        outcome.study_name + ": floor " + number + " (DOF " + number + "), every case", "time (s)",
        "displacement (mm)"};
    const auto add = [&](const CaseOutcome& c, const std::string& label, const std::string& style) {
      const Eigen::Index column = c.simulation.column_of_dof(dof);
      if (column < 0) return;
      util::Series s{label, c.simulation.time, {}, style};
      for (Eigen::Index k = 0; k < c.simulation.displacement.rows(); ++k)
        s.y.push_back(c.simulation.displacement(k, column) * 1e3);
      s.x.resize(s.y.size());
      panel.series.push_back(std::move(s));
    };
    for (std::size_t i = 0; i < drawn.size(); ++i)
      if (drawn[i] != &reference && bounded(*drawn[i]))
        add(*drawn[i], drawn[i]->name, case_style(i));
    add(reference, "reference: " + reference.name + " (drawn over)", kReferenceStyle);
    panel.height = 340;
    panel.columns = 2;
    panels.push_back(std::move(panel));
  }
  return panels;
}

// Actuator a's two panels: tracking error over time and force against command, every bounded
// case that drove it.
std::vector<util::PlotSpec> actuator_panels(const std::vector<const CaseOutcome*>& drawn,
                                            const ActuatorNames& names, int a) {
  util::PlotSpec tracking{names.of(a) + ": tracking error", "time (s)", "x_m - x_t (mm)"};
  util::PlotSpec loop{names.of(a) + ": force against command", "command (mm)", "force (kN)"};
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    const CaseOutcome& c = *drawn[i];
    const core::SimulationResult& r = c.simulation;
    if (!bounded(c) || r.command.cols() <= a || r.realised.cols() <= a) continue;
    util::Series error{c.name, r.time, {}, case_style(i, "lines", "lw 1.5")};
    for (Eigen::Index k = 0; k < r.command.rows(); ++k)
      error.y.push_back((r.realised(k, a) - r.command(k, a)) * 1e3);
    error.x.resize(error.y.size());
    tracking.series.push_back(std::move(error));
    loop.series.push_back(force_loop(c, a, c.name, case_style(i, "lines", "lw 1.5")));
  }
  for (util::PlotSpec* p : {&tracking, &loop}) {
    p->width = kActuatorPanelWidth;
    p->height = kActuatorPanelHeight;
    p->columns = kActuatorColumns;
    p->max_x_tics = kActuatorTics;
    p->one_legend_below = true;  // every panel draws the same cases in the same colours
  }
  return {tracking, loop};
}

// actuators_<p>.png, one figure a page.
std::vector<util::Figure> actuator_pages(const StudyOutcome& outcome,
                                         const std::vector<const CaseOutcome*>& drawn,
                                         const std::filesystem::path& directory) {
  std::vector<util::Figure> pages;
  const std::vector<int>& order = outcome.actuators.order;
  for (std::size_t first = 0; first < order.size(); first += kActuatorsPerPage) {
    util::Figure page{
        {}, directory / ("actuators_" + std::to_string(first / kActuatorsPerPage + 1) + ".png")};
    const std::size_t end = std::min(order.size(), first + kActuatorsPerPage);
    for (std::size_t i = first; i < end; ++i)
      for (util::PlotSpec& panel : actuator_panels(drawn, outcome.actuators, order[i]))
        if (!panel.series.empty()) page.panels.push_back(std::move(panel));
    if (!page.panels.empty()) pages.push_back(std::move(page));
  }
  return pages;
}

// The actuators_<p>.png / .svg pages `directory` holds, by page number (a longer number after a
// shorter one), a page's PNG before its SVG.
std::vector<std::string> actuator_page_files(const std::filesystem::path& directory) {
  std::vector<std::string> pages;
  if (!std::filesystem::is_directory(directory)) return pages;
  const std::regex page("actuators_[0-9]+\\.(png|svg)");
  for (const auto& entry : std::filesystem::directory_iterator(directory))
    if (std::regex_match(entry.path().filename().string(), page))
      pages.push_back(entry.path().filename().string());
  std::sort(pages.begin(), pages.end(), [](const std::string& a, const std::string& b) {
    return a.size() != b.size() ? a.size() < b.size() : a < b;
  });
  return pages;
}

}  // namespace

std::vector<util::Figure> many_dof_figures(const StudyOutcome& outcome,
                                           const std::vector<const CaseOutcome*>& drawn,
                                           const std::filesystem::path& directory) {
  std::vector<util::Figure> figures;
  const std::vector<int> floors = recorded_floors(outcome.reference().simulation);
  if (floors.size() >= static_cast<std::size_t>(kEnvelopeFloors) && bounded(outcome.reference())) {
    figures.push_back(
        {envelope_panels(outcome, drawn, floors), directory / "response_envelope.png"});
    figures.push_back({history_panels(outcome, drawn, floors), directory / "floor_histories.png"});
  }
  if (outcome.actuators.order.size() >= 2)
    for (util::Figure& page : actuator_pages(outcome, drawn, directory))
      figures.push_back(std::move(page));
  return figures;
}

void remove_many_dof_figures(const std::filesystem::path& directory) {
  for (const char* stale : {"response_envelope.png", "response_envelope.svg", "floor_histories.png",
                            "floor_histories.svg"})
    std::filesystem::remove(directory / stale);
  for (const std::string& page : actuator_page_files(directory))
    std::filesystem::remove(directory / page);
}

std::vector<std::string> study_plot_files(const std::filesystem::path& directory) {
  std::vector<std::string> files = study_plot_files();
  for (std::string& page : actuator_page_files(directory)) files.push_back(std::move(page));
  return files;
}

}  // namespace rths::analysis
