#include "analysis/benchmark/benchmark_plots.h"

#include <cmath>
#include <sstream>

#include "core/benchmark_criteria.h"
#include "util/plot.h"

namespace rths::analysis {
namespace {

// The criteria of a case as reported: J1 in ms, J2-J9 in %.
std::array<double, 9> as_reported(const core::BenchmarkCriteria& c) {
  std::array<double, 9> j = c.j;
  j[0] *= 1e3;
  return j;
}

// One panel of criteria [first, last] (1-based J numbers): a bar (a thick impulse) per case at
// each criterion, the cases side by side; the published values as black marks.
util::PlotSpec criteria_panel(const BenchmarkEvaluation& e, int first, int last,
                              const std::string& unit) {
  const auto& definitions = core::criterion_definitions();
  // Titles streamed: `"J" + std::to_string(...)` trips GCC 12's false -Wrestrict (bug 105329).
  std::ostringstream title;
  if (first == last)
    title << definitions[first - 1].name << ": " << definitions[first - 1].definition;
  else
    title << "J" << first << "-J" << last
          << ": tracking and response errors against the exact response";
  util::PlotSpec p{title.str(), "", unit};
  p.height = 380;
  const double cases = static_cast<double>(e.cases.size());
  const double spread = std::min(0.7, 0.18 * cases);  // of the unit between criteria
  for (std::size_t c = 0; c < e.cases.size(); ++c) {
    util::Series bars{e.cases[c].name, {}, {}, "impulses lw 14"};
    const std::array<double, 9> j = as_reported(e.cases[c].criteria);
    const double offset =
        cases > 1 ? -spread / 2 + spread * static_cast<double>(c) / (cases - 1) : 0.0;
    for (int k = first; k <= last; ++k) {
      if (!std::isfinite(j[k - 1])) continue;
      bars.x.push_back(k + offset);
      bars.y.push_back(j[k - 1]);
    }
    p.series.push_back(std::move(bars));
  }
  if (!e.published.empty() && e.published_motion_matches) {
    util::Series marks{
        "published (" + e.published_case + ")", {}, {}, "points pt 7 ps 1.6 lc rgb 'black'"};
    for (int k = first; k <= last; ++k) {
      marks.x.push_back(k);
      marks.y.push_back(e.published[static_cast<std::size_t>(k - 1)]);
    }
    p.series.push_back(std::move(marks));
  }
  for (int k = first; k <= last; ++k) p.x_labels.emplace_back(k, definitions[k - 1].name);
  p.x_min = first - 0.6;
  p.x_max = last + 0.6;
  p.y_min = 0.0;
  return p;
}

// Floor `floor` (0-based) of the exact response and of each bounded judged case, in mm.
util::PlotSpec floor_panel(const BenchmarkEvaluation& e, const StudyOutcome& outcome, int floor) {
  std::ostringstream title;
  title << "floor " << floor + 1 << " (the experimental storey is floor " << e.experimental_dof + 1
        << ")";
  util::PlotSpec p{title.str(), "time (s)", "displacement (mm)"};
  p.height = 380;
  for (const BenchmarkCaseCriteria& judged : e.cases)
    for (const CaseOutcome& c : outcome.cases) {
      if (c.name != judged.name || c.diverged()) continue;
      util::Series s{c.name, {}, {}, "lines lw 2"};
      for (Eigen::Index k = 0; k < c.simulation.displacement.rows(); ++k) {
        s.x.push_back(static_cast<double>(k) * c.simulation.dt);
        s.y.push_back(c.simulation.displacement(k, floor) * 1e3);
      }
      p.series.push_back(std::move(s));
    }
  // Drawn last, on top of the cases it judges.
  util::Series exact{"exact response of the whole structure", {}, {}, "lines lw 1 lc rgb 'black'"};
  for (Eigen::Index k = 0; k < e.reference_displacement.rows(); ++k) {
    exact.x.push_back(static_cast<double>(k) * e.dt);
    exact.y.push_back(e.reference_displacement(k, floor) * 1e3);
  }
  p.series.push_back(std::move(exact));
  p.x_min = 0.0;
  p.x_max = static_cast<double>(e.reference_displacement.rows() - 1) * e.dt;
  return p;
}

}  // namespace

std::vector<std::string> benchmark_plot_files() {
  return {"benchmark_criteria.png", "benchmark_criteria.svg", "benchmark_floors.png",
          "benchmark_floors.svg"};
}

std::vector<std::filesystem::path> write_benchmark_plots(const BenchmarkEvaluation& evaluation,
                                                         const StudyOutcome& outcome,
                                                         const std::filesystem::path& directory) {
  std::vector<std::filesystem::path> written;
  if (evaluation.cases.empty()) return written;
  const auto criteria = directory / "benchmark_criteria.png";
  util::write_png_panels(
      {criteria_panel(evaluation, 1, 1, "J1 (ms)"), criteria_panel(evaluation, 2, 9, "J (%)")},
      criteria);
  written.push_back(criteria);
  std::vector<util::PlotSpec> floors;
  for (int floor = 0;
       floor < static_cast<int>(evaluation.reference_displacement.cols()) && floors.size() < 2;
       ++floor)
    if (floor != evaluation.experimental_dof)
      floors.push_back(floor_panel(evaluation, outcome, floor));
  if (!floors.empty()) {
    const auto path = directory / "benchmark_floors.png";
    util::write_png_panels(floors, path);
    written.push_back(path);
  }
  return written;
}

}  // namespace rths::analysis
