#include "analysis/tables/result_tables.h"

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

namespace {

using Channel = study::RecordedChannel;

// The channels of a table: the recorders', or (an outcome without them) every DOF the case kept
// and the actuators.
std::vector<Channel> table_channels(const StudyOutcome& outcome) {
  if (!outcome.recorders.channels.empty()) return outcome.recorders.channels;
  std::vector<Channel> channels;
  const core::SimulationResult& first = outcome.cases.front().simulation;
  for (Eigen::Index c = 0; c < first.displacement.cols(); ++c)
    channels.push_back({Channel::Kind::kDisplacement,
                        first.dofs.empty() ? static_cast<int>(c) : first.dofs[c], -1, 1});
  channels.push_back({Channel::Kind::kActuators, -1, -1, 1});
  return channels;
}

// The steps (rows) some channel keeps, below `steps`.
std::vector<std::size_t> kept_steps(const std::vector<Channel>& channels, std::size_t steps) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < steps; ++k)
    if (std::any_of(channels.begin(), channels.end(), [k](const Channel& c) { return c.keeps(k); }))
      out.push_back(k);
  return out;
}

// One column at the table's rows: value(k) at the steps the channel keeps and the case ran,
// NaN elsewhere.
template <typename Value>
std::vector<double> sampled(const std::vector<std::size_t>& rows, const Channel& channel,
                            std::size_t steps, Value value) {
  std::vector<double> out(rows.size(), kMissing);
  for (std::size_t r = 0; r < rows.size(); ++r)
    if (rows[r] < steps && channel.keeps(rows[r])) out[r] = value(rows[r]);
  return out;
}

// The history the case kept of `dof` (0-based); throws naming the DOF when it kept none.
Eigen::Index kept_column(const core::SimulationResult& r, int dof, const std::string& name) {
  const Eigen::Index column = r.column_of_dof(dof);
  if (column < 0)
    throw std::invalid_argument("case '" + name + "' kept no history of DOF " +
                                std::to_string(dof + 1));
  return column;
}

// The columns of one channel of one case.
void add_channel_columns(results::Table& table, const CaseOutcome& c, const Channel& channel,
                         const std::vector<std::size_t>& rows) {
  const core::SimulationResult& r = c.simulation;
  const std::string prefix = results::result_column_prefix(c.name);
  const std::size_t steps = r.steps();
  const auto at = [](const core::Mat& m, Eigen::Index column) {
    return [&m, column](std::size_t k) { return m(static_cast<Eigen::Index>(k), column); };
  };
  const auto floor = static_cast<std::size_t>(channel.dof + 1);
  switch (channel.kind) {
    case Channel::Kind::kDisplacement:
      table.add_numbers(
          prefix + results::displacement_column(floor), "m",
          sampled(rows, channel, steps, at(r.displacement, kept_column(r, channel.dof, c.name))));
      return;
    case Channel::Kind::kVelocity:
      table.add_numbers(
          prefix + results::velocity_column(floor), "m/s",
          sampled(rows, channel, steps, at(r.velocity, kept_column(r, channel.dof, c.name))));
      return;
    case Channel::Kind::kAcceleration:
      table.add_numbers(
          prefix + results::acceleration_column(floor), "m/s^2",
          sampled(rows, channel, steps, at(r.acceleration, kept_column(r, channel.dof, c.name))));
      return;
    case Channel::Kind::kDrift: {
      const Eigen::Index upper = kept_column(r, channel.dof, c.name);
      const Eigen::Index lower =
          channel.from_dof < 0 ? -1 : kept_column(r, channel.from_dof, c.name);
      table.add_numbers(
          prefix + results::drift_column(floor, static_cast<std::size_t>(channel.from_dof + 1)),
          "m", sampled(rows, channel, steps, [&](std::size_t k) {
            const auto row = static_cast<Eigen::Index>(k);
            return r.displacement(row, upper) - (lower < 0 ? 0.0 : r.displacement(row, lower));
          }));
      return;
    }
    case Channel::Kind::kBaseShear:
      table.add_numbers(prefix + results::kBaseShearColumn, "N",
                        sampled(rows, channel, std::min(steps, r.base_shear.size()),
                                [&r](std::size_t k) { return r.base_shear[k]; }));
      return;
    case Channel::Kind::kActuators:
      for (Eigen::Index j = 0; j < r.command.cols(); ++j) {
        const auto actuator = static_cast<std::size_t>(j + 1);
        table.add_numbers(prefix + results::command_column(actuator), "m",
                          sampled(rows, channel, steps, at(r.command, j)));
        table.add_numbers(prefix + results::measured_column(actuator), "m",
                          sampled(rows, channel, steps, at(r.realised, j)));
        table.add_numbers(prefix + results::force_column(actuator), "N",
                          sampled(rows, channel, steps, at(r.measured_force, j)));
      }
      return;
  }
}

}  // namespace

results::Table study_table(const StudyOutcome& outcome) {
  results::Table table;
  if (outcome.cases.empty()) return table;
  std::size_t steps = 0;
  for (const auto& c : outcome.cases) steps = std::max(steps, c.simulation.steps());
  const double dt = outcome.cases.front().simulation.dt;
  const std::vector<Channel> channels = table_channels(outcome);
  const std::vector<std::size_t> rows = kept_steps(channels, steps);
  std::vector<double> step(rows.size()), time(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    step[r] = static_cast<double>(rows[r]);
    time[r] = static_cast<double>(rows[r]) * dt;
  }
  table.add_numbers("step", "", std::move(step));
  table.add_numbers("time_s", "s", std::move(time));
  // Each case's channels (results/column_names.h names); a case that stopped early is NaN (an
  // empty CSV cell) after its last step, a channel NaN at the steps it does not keep.
  for (const auto& c : outcome.cases)
    for (const Channel& channel : channels) add_channel_columns(table, c, channel, rows);
  table.set_attribute("study", outcome.study_name);
  table.set_number_attribute("dt_s", dt);
  results::set_motion_attributes(table, outcome.motion_name, outcome.motion_sha256,
                                 outcome.motion_file_sha256);
  set_study_verdict(table, outcome);
  table.set_attribute("reference_case", outcome.reference().name);
  table.set_attribute("reference", outcome.reference_description());
  return table;
}

TableShape study_table_shape(const study::RecorderPlan& plan, std::size_t steps, std::size_t cases,
                             std::size_t actuators) {
  const std::size_t per_case = plan.columns_per_case(actuators);
  std::size_t rows = 0;
  for (std::size_t k = 0; k < steps; ++k) rows += plan.keeps(k) ? 1 : 0;
  return {rows, 2 + cases * per_case};
}

results::Table distributed_study_table(
    const StudyOutcome& outcome, const std::vector<std::map<int, runtime::LinkSeries>>& links) {
  if (links.size() != outcome.cases.size())
    throw std::invalid_argument("distributed_study_table: " + std::to_string(links.size()) +
                                " link sets for " + std::to_string(outcome.cases.size()) +
                                " cases");
  results::Table table = study_table(outcome);
  const std::size_t rows = table.rows();
  // The row of each step the table keeps (its recorders may keep every k-th).
  std::map<long long, std::size_t> row_of_step;
  const std::vector<double>& steps = table.column("step").numbers;
  for (std::size_t r = 0; r < rows; ++r) row_of_step[std::llround(steps[r])] = r;
  for (std::size_t i = 0; i < links.size(); ++i) {
    const core::SimulationResult& r = outcome.cases[i].simulation;
    const std::string prefix = results::result_column_prefix(outcome.cases[i].name);
    for (const auto& [node, series] : links[i]) {
      std::vector<double> injected(rows, kMissing), round_trip(rows, kMissing);
      for (std::size_t a = 0; a < series.time.size(); ++a) {
        // The carrying step's index from its simulated time t_k = k dt.
        const auto row = row_of_step.find(r.dt > 0 ? std::llround(series.time[a] / r.dt) : -1);
        if (row == row_of_step.end()) continue;
        injected[row->second] = series.injected[a];
        round_trip[row->second] = series.round_trip[a];
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
