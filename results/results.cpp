#include "results/results.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/ground_motion.h"
#include "results/column_names.h"
#include "study/motion_key.h"

namespace rths::results {
namespace {

constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();

}  // namespace

std::string link_column(int node, const std::string& quantity) {
  std::string name = "node";  // appended: GCC 12 misreads `"node" + std::to_string` (-Wrestrict)
  name += std::to_string(node);
  name += '_';
  name += quantity;
  return name;
}

void set_motion_attributes(Table& t, const std::string& name, const std::string& sha256,
                           const std::string& file_sha256) {
  t.set_attribute("motion_name", name);
  t.set_attribute("motion_sha256", sha256);
  t.set_attribute("motion_file_sha256", file_sha256);
}

namespace {

// The run's identity and integrity as table attributes.
void set_record_attributes(const runtime::RecordContents& record, Table& t) {
  const runtime::RunHeader* header = record.header_or_assumed();
  t.set_attribute("run_id", header->run_id());
  t.set_attribute("case_name", header->case_name());
  t.set_attribute("clock", header->clock());
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

// What the run ran and its verdict, named as a study's table names them: study, dt_s, the motion
// (from the inputs entry, where the record carries it as run; a record without one names only
// the file checksum its config required, if any), status and ok (1: the footer says the run
// succeeded; 0: it failed or has no footer).
void set_run_facts(const runtime::RecordContents& record, Table& t) {
  const runtime::RunHeader* header = record.header_or_assumed();
  const config::Study* study = record.study_as_run();
  if (!study) study = &header->study();
  t.set_attribute("study", study->name());
  t.set_number_attribute("dt_s", header->dt());
  const config::GroundMotion& motion = study->motion();
  if (motion.has_embedded()) {
    const config::EmbeddedMotion& e = motion.embedded();
    const core::GroundMotion as_run{
        .name = e.name(),
        .dt = e.dt(),
        .acceleration = {e.acceleration().begin(), e.acceleration().end()}};
    set_motion_attributes(t, e.name(), study::motion_key(as_run), e.source_sha256());
  } else {
    set_motion_attributes(t, "", "", motion.sha256());
  }
  const runtime::RunFooter* footer = record.footer();
  t.set_attribute("status", footer ? footer->status() : "no footer: the run was cut short");
  t.set_number_attribute("ok", footer && footer->ok() ? 1.0 : 0.0);
}

// Whether the run's deployment has node `id` as a CONTROLLER (its links carry the frame's round
// trip and the controller's status).
const config::NodeSpec* controller_node(const runtime::RunHeader& header, int id) {
  for (const auto& node : header.study().deployment().nodes())
    if (node.id() == id) return node.kind() == config::NodeSpec::CONTROLLER ? &node : nullptr;
  return nullptr;
}

// A controller's diagnostic channels on link `l` (LinkSample.controller_diagnostics, SI), one
// column each, named by the layout's DIAGNOSTIC fields (node<id>_diag_<name>, no unit suffix).
void add_diagnostic_columns(Table& t, const config::NodeSpec& node, std::size_t l,
                            const std::vector<const runtime::StepRecord*>& steps) {
  int channel = 0;
  for (const auto& f : node.controller().feedback().fields()) {
    if (f.role() != config::FrameField::DIAGNOSTIC) continue;
    std::vector<double> out;
    out.reserve(steps.size());
    for (const auto* s : steps) {
      const bool has = l < static_cast<std::size_t>(s->links_size()) &&
                       channel < s->links(static_cast<int>(l)).controller_diagnostics_size();
      out.push_back(has ? s->links(static_cast<int>(l)).controller_diagnostics(channel) : kMissing);
    }
    // SI values whose unit the layout states for people only: no unit suffix.
    t.add_numbers(identifier(link_column(node.id(), "diag_" + f.name())), "", std::move(out));
    ++channel;
  }
}

// Per link of the header, its samples' columns (node<id>_...): a step without this link's sample
// (step 0 has no exchange) is missing, not zero.
// A force predictor's error on link `l` (to node `id`), one column per actuator of the node
// (LinkSample.prediction_error, N); none when no step carries one (no predictor on the link).
void add_prediction_error_columns(Table& t, int id, std::size_t l,
                                  const std::vector<const runtime::StepRecord*>& steps) {
  std::size_t actuators = 0;
  for (const auto* s : steps)
    if (l < static_cast<std::size_t>(s->links_size()))
      actuators = std::max<std::size_t>(
          actuators,
          static_cast<std::size_t>(s->links(static_cast<int>(l)).prediction_error_size()));
  for (std::size_t a = 0; a < actuators; ++a) {
    std::vector<double> out;
    out.reserve(steps.size());
    for (const auto* s : steps) {
      const bool has =
          l < static_cast<std::size_t>(s->links_size()) &&
          a < static_cast<std::size_t>(s->links(static_cast<int>(l)).prediction_error_size());
      out.push_back(has ? s->links(static_cast<int>(l)).prediction_error(static_cast<int>(a))
                        : kMissing);
    }
    std::string quantity = "prediction_error";
    quantity += std::to_string(a + 1);
    quantity += "_N";
    t.add_numbers(link_column(id, quantity), "N", std::move(out));
  }
}

void add_link_columns(Table& t, const runtime::RunHeader& header,
                      const std::vector<const runtime::StepRecord*>& steps) {
  const auto links = static_cast<std::size_t>(header.link_node_ids_size());
  for (std::size_t l = 0; l < links; ++l) {
    const int id = header.link_node_ids(static_cast<int>(l));
    const auto column = [id](const std::string& quantity) { return link_column(id, quantity); };
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
    t.add_numbers(column("answered_step"), "",
                  link([](const Link& x) { return x.answered_step(); }));
    t.add_numbers(column("injected_lag_s"), "s",
                  link([](const Link& x) { return x.injected_lag(); }));
    t.add_numbers(column("round_trip_s"), "s", link([](const Link& x) { return x.round_trip(); }));
    t.add_numbers(column("one_way_down_s"), "s",
                  link([](const Link& x) { return x.one_way_down(); }));
    t.add_numbers(column("one_way_up_s"), "s", link([](const Link& x) { return x.one_way_up(); }));
    add_prediction_error_columns(t, id, l, steps);
    const config::NodeSpec* controller = controller_node(header, id);
    if (!controller) continue;
    t.add_numbers(column("controller_round_trip_s"), "s",
                  link([](const Link& x) { return x.controller_round_trip(); }));
    t.add_numbers(column("controller_status"), "",
                  link([](const Link& x) { return x.controller_status(); }));
    add_diagnostic_columns(t, *controller, l, steps);
  }
}

// Column i of one repeated field of every step (zero where a step carries fewer values), named by
// results/column_names.h with numbers[i] (1-based): a DOF's is the one the header's recorded_dofs
// gives it (every DOF when it names none), an actuator's its index.
template <class Field>
void add_numbered(Table& t, const std::vector<const runtime::StepRecord*>& steps,
                  std::string (*name)(std::size_t), const std::string& unit,
                  const std::vector<std::size_t>& numbers, Field field) {
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    std::vector<double> column(steps.size(), 0.0);
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const auto& values = field(*steps[k]);
      if (static_cast<int>(i) < values.size()) column[k] = values.Get(static_cast<int>(i));
    }
    t.add_numbers(name(numbers[i]), unit, std::move(column));
  }
}

}  // namespace

Table record_table(const runtime::RecordContents& record) {
  const runtime::RunHeader* header = record.header_or_assumed();
  if (!header) throw std::invalid_argument("the run record has no header entry and no step");
  const std::vector<const runtime::StepRecord*> steps = record.steps();
  std::vector<std::size_t> dofs, actuators;  // 1-based numbers of the columns
  for (const int dof : runtime::recorded_dofs(*header))
    dofs.push_back(static_cast<std::size_t>(dof) + 1);
  for (int a = 1; a <= header->actuators(); ++a) actuators.push_back(static_cast<std::size_t>(a));

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
  add_numbered(
      t, steps, displacement_column, "m", dofs,
      [](const Step& s) -> const auto& { return s.displacement(); });
  add_numbered(
      t, steps, velocity_column, "m/s", dofs,
      [](const Step& s) -> const auto& { return s.velocity(); });
  add_numbered(
      t, steps, acceleration_column, "m/s^2", dofs,
      [](const Step& s) -> const auto& { return s.acceleration(); });
  add_numbered(
      t, steps, command_column, "m", actuators,
      [](const Step& s) -> const auto& { return s.command(); });
  add_numbered(
      t, steps, measured_column, "m", actuators,
      [](const Step& s) -> const auto& { return s.realised(); });
  add_numbered(
      t, steps, force_column, "N", actuators,
      [](const Step& s) -> const auto& { return s.measured_force(); });
  add_link_columns(t, *header, steps);
  t.add_numbers("lateness_s", "s", scalar([](const Step& s) { return s.lateness(); }));
  t.add_numbers("overrun", "", scalar([](const Step& s) { return s.overrun() ? 1 : 0; }));
  set_record_attributes(record, t);
  set_run_facts(record, t);
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
