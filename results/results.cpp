#include "results/results.h"

#include <algorithm>
#include <cmath>

#include "analysis/results_csv.h"

#include <limits>
#include <stdexcept>

namespace rths::results {
namespace {

constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();

}  // namespace

Table study_table(const analysis::StudyOutcome& outcome) {
  Table table;
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
  // Every floor and every actuator of every case (analysis/results_csv.h names); a case that
  // stopped early is NaN (an empty CSV cell) after its last step.
  for (const auto& c : outcome.cases) {
    const core::SimulationResult& r = c.simulation;
    const std::vector<std::string> names = analysis::result_column_names(c.name, r);
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
  table.set_attribute("reference_case", outcome.reference().name);
  table.set_attribute("reference", outcome.reference_description());
  return table;
}

Table distributed_study_table(const analysis::StudyOutcome& outcome,
                              const std::vector<std::map<int, runtime::LinkSeries>>& links) {
  if (links.size() != outcome.cases.size())
    throw std::invalid_argument("distributed_study_table: " + std::to_string(links.size()) +
                                " link sets for " + std::to_string(outcome.cases.size()) +
                                " cases");
  Table table = study_table(outcome);
  const std::size_t rows = table.rows();
  for (std::size_t i = 0; i < links.size(); ++i) {
    const core::SimulationResult& r = outcome.cases[i].simulation;
    const std::string prefix = analysis::result_column_prefix(outcome.cases[i].name) + "lag_node";
    for (const auto& [node, series] : links[i]) {
      std::vector<double> injected(rows, kMissing), round_trip(rows, kMissing);
      for (std::size_t a = 0; a < series.time.size(); ++a) {
        // The carrying step's index from its simulated time t_k = k dt.
        const auto k = r.dt > 0 ? std::llround(series.time[a] / r.dt) : -1;
        if (k < 0 || static_cast<std::size_t>(k) >= rows) continue;
        injected[static_cast<std::size_t>(k)] = series.injected[a];
        round_trip[static_cast<std::size_t>(k)] = series.round_trip[a];
      }
      const std::string name = prefix + std::to_string(node);
      table.add_numbers(name + "_injected_s", "s", std::move(injected));
      table.add_numbers(name + "_round_trip_s", "s", std::move(round_trip));
    }
  }
  return table;
}

Table sweep_table(const std::vector<analysis::SweepTableRow>& rows, const std::string& grid_hash,
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
  using Row = analysis::SweepTableRow;
  Table t;
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
  t.add_numbers("eq2_paper", "", numbers([](const Row& r) { return r.eq2_paper; }));
  t.add_numbers("nrmse_pct", "%", numbers([](const Row& r) { return r.nrmse_pct; }));
  t.add_numbers("peak_error_m", "m", numbers([](const Row& r) { return r.peak_error; }));
  t.add_numbers("diverged", "", numbers([](const Row& r) { return r.diverged ? 1 : 0; }));
  t.set_attribute("grid_hash", grid_hash);
  t.set_attribute("grid_points", std::to_string(grid_points));
  return t;
}

namespace {

// The run's identity, outcome and integrity as table attributes.
void set_record_attributes(const runtime::RecordContents& record, Table& t) {
  const runtime::RunHeader* header = record.header_or_assumed();
  t.set_attribute("run_id", header->run_id());
  t.set_attribute("case_name", header->case_name());
  t.set_attribute("clock", header->clock());
  const runtime::RunFooter* footer = record.footer();
  t.set_attribute("status", footer ? footer->status() : "no footer: the run was cut short");
  t.set_attribute("integrity", (!record.checksummed     ? "unverified: written without checksums"
                                : record.lost_entries() ? "damaged: " + record.loss_report()
                                                        : "verified (CRC-32C per entry)") +
                                   (record.assumed.empty() ? "" : "; " + record.assumed));
  std::string lost;
  // Appended piece by piece: GCC 12 misreads `"-" + std::to_string(...)` here (-Wrestrict).
  for (const auto& [first, last] : record.missing_steps()) {
    if (!lost.empty()) lost += ',';
    lost += std::to_string(first);
    if (last > first) {
      lost += '-';
      lost += std::to_string(last);
    }
  }
  t.set_attribute("lost_steps", lost);
}

// Whether the run's deployment has node `id` as a CONTROLLER (its links carry the frame's round
// trip and the controller's status).
bool is_controller(const runtime::RunHeader& header, int id) {
  for (const auto& node : header.study().deployment().nodes())
    if (node.id() == id) return node.kind() == config::NodeSpec::CONTROLLER;
  return false;
}

// Per link of the header, its samples' columns (node<id>_...): a step without this link's sample
// (step 0 has no exchange) is missing, not zero.
void add_link_columns(Table& t, const runtime::RunHeader& header,
                      const std::vector<const runtime::StepRecord*>& steps) {
  const auto links = static_cast<std::size_t>(header.link_node_ids_size());
  for (std::size_t l = 0; l < links; ++l) {
    const int id = header.link_node_ids(static_cast<int>(l));
    const std::string prefix = "node" + std::to_string(id) + "_";
    const auto link = [&steps, l](auto field) {
      std::vector<double> out;
      out.reserve(steps.size());
      for (const auto* s : steps) {
        out.push_back(l < static_cast<std::size_t>(s->links_size())
                          ? static_cast<double>(field(s->links(static_cast<int>(l))))
                          : kMissing);
      }
      return out;
    };
    using Link = runtime::LinkSample;
    t.add_numbers(prefix + "answered_step", "",
                  link([](const Link& x) { return x.answered_step(); }));
    t.add_numbers(prefix + "injected_lag_s", "s",
                  link([](const Link& x) { return x.injected_lag(); }));
    t.add_numbers(prefix + "round_trip_s", "s", link([](const Link& x) { return x.round_trip(); }));
    t.add_numbers(prefix + "one_way_down_s", "s",
                  link([](const Link& x) { return x.one_way_down(); }));
    t.add_numbers(prefix + "one_way_up_s", "s", link([](const Link& x) { return x.one_way_up(); }));
    if (!is_controller(header, id)) continue;
    t.add_numbers(prefix + "controller_round_trip_s", "s",
                  link([](const Link& x) { return x.controller_round_trip(); }));
    t.add_numbers(prefix + "controller_status", "",
                  link([](const Link& x) { return x.controller_status(); }));
  }
}

}  // namespace

Table record_table(const runtime::RecordContents& record) {
  const runtime::RunHeader* header = record.header_or_assumed();
  if (!header) throw std::invalid_argument("the run record has no header entry and no step");
  const std::vector<const runtime::StepRecord*> steps = record.steps();
  const auto dofs = static_cast<std::size_t>(header->dofs());
  const auto actuators = static_cast<std::size_t>(header->actuators());

  // Per-step values of one repeated field, zero where a step carries fewer entries.
  const auto per_index = [&steps](auto field, std::size_t count) {
    std::vector<std::vector<double>> out(count, std::vector<double>(steps.size(), 0.0));
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const auto& values = field(*steps[k]);
      for (std::size_t i = 0; i < count && static_cast<int>(i) < values.size(); ++i) {
        out[i][k] = values.Get(static_cast<int>(i));
      }
    }
    return out;
  };
  const auto scalar = [&steps](auto field) {
    std::vector<double> out;
    out.reserve(steps.size());
    for (const auto* s : steps) out.push_back(static_cast<double>(field(*s)));
    return out;
  };
  using Step = runtime::StepRecord;
  Table t;
  t.add_numbers("step", "", scalar([](const Step& s) { return s.step(); }));
  t.add_numbers("time_s", "s", scalar([](const Step& s) { return s.time(); }));
  t.add_numbers("ground_acceleration_m_per_s2", "m/s^2",
                scalar([](const Step& s) { return s.ground_acceleration(); }));
  const auto add_indexed = [&t](const std::string& name, const std::string& unit,
                                std::vector<std::vector<double>> columns) {
    for (std::size_t i = 0; i < columns.size(); ++i)
      t.add_numbers(name + std::to_string(i + 1) + "_" + unit_suffix(unit), unit,
                    std::move(columns[i]));
  };
  add_indexed("u", "m",
              per_index(
                  [](const Step& s) -> const auto& { return s.displacement(); }, dofs));
  add_indexed("v", "m/s",
              per_index(
                  [](const Step& s) -> const auto& { return s.velocity(); }, dofs));
  add_indexed("a", "m/s^2",
              per_index(
                  [](const Step& s) -> const auto& { return s.acceleration(); }, dofs));
  add_indexed("command", "m",
              per_index(
                  [](const Step& s) -> const auto& { return s.command(); }, actuators));
  add_indexed("realised", "m",
              per_index(
                  [](const Step& s) -> const auto& { return s.realised(); }, actuators));
  add_indexed("force", "N",
              per_index(
                  [](const Step& s) -> const auto& { return s.measured_force(); }, actuators));
  add_link_columns(t, *header, steps);
  t.add_numbers("lateness_s", "s", scalar([](const Step& s) { return s.lateness(); }));
  t.add_numbers("overrun", "", scalar([](const Step& s) { return s.overrun() ? 1 : 0; }));
  set_record_attributes(record, t);
  return t;
}

Table identify_table(const identify::Identification& identification) {
  Table t;
  std::vector<double> time;
  for (const auto& s : identification.signals) {
    if (s.time.size() > time.size()) time = s.time;
  }
  const std::size_t rows = time.size();
  t.add_numbers("time_s", "s", std::move(time));
  const auto padded = [rows](std::vector<double> v) {
    v.resize(rows, kMissing);
    return v;
  };
  for (const auto& c : identification.channels) {
    const identify::ChannelSignals* signals = nullptr;
    for (const auto& s : identification.signals) {
      if (s.channel == c.channel) signals = &s;
    }
    if (!signals) continue;
    const std::string name = identify::channel_name(c.channel);
    const std::string unit = c.channel == identify::Channel::kMeasured ? "m" : "N";
    t.add_numbers(name + "_input_m", "m", padded(signals->input));
    t.add_numbers(name + "_target_" + unit, unit, padded(signals->target));
    t.add_numbers(name + "_declared_" + unit, unit, padded(c.declared_fit.prediction));
    t.add_numbers(name + "_final_" + unit, unit, padded(c.final_fit.prediction));
  }
  t.set_attribute("source", identification.source);
  return t;
}

}  // namespace rths::results
