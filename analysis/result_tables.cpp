#include "analysis/result_tables.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "results/column_names.h"
#include "results/results.h"

namespace rths::analysis {
namespace {

constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();

// A case ran as meant: it completed, or diverged as its expect_unstable said it would.
bool case_ok(const CaseOutcome& c) {
  return c.status == "completed" || (c.diverged() && c.expect_unstable);
}

// The study's verdict over its cases: status "completed" when every case completed, else
// "<case>: <status>" of each case that did not; ok 1 when every case ran as meant, else 0.
void set_study_verdict(results::Table& t, const StudyOutcome& outcome) {
  std::string status;
  bool ok = true;
  for (const CaseOutcome& c : outcome.cases) {
    ok = ok && case_ok(c);
    if (c.status == "completed") continue;
    if (!status.empty()) status += "; ";
    status += c.name + ": " + c.status;
  }
  t.set_attribute("status", status.empty() ? "completed" : status);
  t.set_number_attribute("ok", ok ? 1.0 : 0.0);
}

}  // namespace

results::Table study_table(const StudyOutcome& outcome) {
  results::Table table;
  if (outcome.cases.empty()) return table;
  std::size_t rows = 0;
  for (const auto& c : outcome.cases) rows = std::max(rows, c.simulation.steps());
  const double dt = outcome.cases.front().simulation.dt;
  std::vector<double> step(rows), time(rows);
  for (std::size_t k = 0; k < rows; ++k) {
    step[k] = static_cast<double>(k);
    time[k] = static_cast<double>(k) * dt;
  }
  table.add_numbers("step", "", std::move(step));
  table.add_numbers("time_s", "s", std::move(time));
  // Every floor and every actuator of every case (results/column_names.h names); a case that
  // stopped early is NaN (an empty CSV cell) after its last step.
  for (const auto& c : outcome.cases) {
    const core::SimulationResult& r = c.simulation;
    const std::vector<std::string> names = results::result_column_names(c.name, r);
    const auto column = [&](const core::Mat& m, Eigen::Index j) {
      std::vector<double> v(rows, kMissing);
      for (Eigen::Index k = 0; k < m.rows(); ++k) v[static_cast<std::size_t>(k)] = m(k, j);
      return v;
    };
    std::size_t n = 0;
    for (Eigen::Index i = 0; i < r.displacement.cols(); ++i)
      table.add_numbers(names[n++], "m", column(r.displacement, i));
    for (Eigen::Index j = 0; j < r.command.cols(); ++j) {
      table.add_numbers(names[n++], "m", column(r.command, j));
      table.add_numbers(names[n++], "m", column(r.realised, j));
      table.add_numbers(names[n++], "N", column(r.measured_force, j));
    }
  }
  table.set_attribute("study", outcome.study_name);
  table.set_number_attribute("dt_s", dt);
  results::set_motion_attributes(table, outcome.motion_name, outcome.motion_sha256,
                                 outcome.motion_file_sha256);
  set_study_verdict(table, outcome);
  table.set_attribute("reference_case", outcome.reference().name);
  table.set_attribute("reference", outcome.reference_description());
  return table;
}

results::Table distributed_study_table(
    const StudyOutcome& outcome, const std::vector<std::map<int, runtime::LinkSeries>>& links) {
  if (links.size() != outcome.cases.size())
    throw std::invalid_argument("distributed_study_table: " + std::to_string(links.size()) +
                                " link sets for " + std::to_string(outcome.cases.size()) +
                                " cases");
  results::Table table = study_table(outcome);
  const std::size_t rows = table.rows();
  for (std::size_t i = 0; i < links.size(); ++i) {
    const core::SimulationResult& r = outcome.cases[i].simulation;
    const std::string prefix = results::result_column_prefix(outcome.cases[i].name);
    for (const auto& [node, series] : links[i]) {
      std::vector<double> injected(rows, kMissing), round_trip(rows, kMissing);
      for (std::size_t a = 0; a < series.time.size(); ++a) {
        // The carrying step's index from its simulated time t_k = k dt.
        const auto k = r.dt > 0 ? std::llround(series.time[a] / r.dt) : -1;
        if (k < 0 || static_cast<std::size_t>(k) >= rows) continue;
        injected[static_cast<std::size_t>(k)] = series.injected[a];
        round_trip[static_cast<std::size_t>(k)] = series.round_trip[a];
      }
      table.add_numbers(prefix + results::link_column(node, "injected_lag_s"), "s",
                        std::move(injected));
      table.add_numbers(prefix + results::link_column(node, "round_trip_s"), "s",
                        std::move(round_trip));
    }
  }
  return table;
}

results::Table sweep_table(const std::vector<SweepTableRow>& rows, const std::string& grid_hash,
                           std::size_t grid_points) {
  const auto numbers = [&rows](auto field) {
    std::vector<double> out;
    out.reserve(rows.size());
    for (const auto& r : rows) out.push_back(static_cast<double>(field(r)));
    return out;
  };
  const auto texts = [&rows](auto field) {
    std::vector<std::string> out;
    for (const auto& r : rows) out.push_back(field(r));
    return out;
  };
  using Row = SweepTableRow;
  results::Table t;
  t.add_numbers("index", "", numbers([](const Row& r) { return r.index; }));
  t.add_numbers("period_s", "s", numbers([](const Row& r) { return r.period; }));
  t.add_numbers("delay_s", "s", numbers([](const Row& r) { return r.delay; }));
  t.add_numbers("alpha", "", numbers([](const Row& r) { return r.alpha; }));
  t.add_numbers("stiffness_N_per_m", "N/m", numbers([](const Row& r) { return r.stiffness; }));
  t.add_numbers("dt_s", "s", numbers([](const Row& r) { return r.dt; }));
  t.add_texts("motion", "", texts([](const Row& r) { return r.motion; }));
  t.add_texts("model", "", texts([](const Row& r) { return r.model; }));
  t.add_numbers("peak_ref_m", "m", numbers([](const Row& r) { return r.peak_reference; }));
  t.add_numbers("peak_delayed_m", "m", numbers([](const Row& r) { return r.peak_delayed; }));
  t.add_numbers("peak_error_pct", "%", numbers([](const Row& r) { return r.peak_error_pct; }));
  t.add_numbers("rms_error_pct", "%", numbers([](const Row& r) { return r.rms_error_pct; }));
  t.add_numbers("peak_error_m", "m", numbers([](const Row& r) { return r.peak_error; }));
  t.add_numbers("nrmse_pct", "%", numbers([](const Row& r) { return r.nrmse_pct; }));
  t.add_numbers("eq2_paper", "", numbers([](const Row& r) { return r.eq2_paper; }));
  t.add_numbers("diverged", "", numbers([](const Row& r) { return r.diverged ? 1 : 0; }));
  t.set_attribute("grid_hash", grid_hash);
  t.set_attribute("grid_points", std::to_string(grid_points));
  return t;
}

}  // namespace rths::analysis
