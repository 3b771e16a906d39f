#include "study/recorders.h"

#include <algorithm>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

namespace rths::study {
namespace {

using Kind = RecordedChannel::Kind;

void require(bool ok, const std::string& source, const std::string& message) {
  if (!ok) throw std::invalid_argument(source + ": " + message);
}

std::string field(int recorder, const std::string& name) {
  return "recorders[" + std::to_string(recorder) + "]." + name;
}

// A 1-based DOF of the config within 1..dofs, as 0-based.
int dof_within(int one_based, int dofs, const std::string& where) {
  if (one_based < 1 || one_based > dofs)
    throw std::invalid_argument(where + ": DOF " + std::to_string(one_based) +
                                " is outside the model's 1.." + std::to_string(dofs));
  return one_based - 1;
}

Kind quantity_kind(int quantity) {
  switch (quantity) {
    case config::Recorder::VELOCITY: return Kind::kVelocity;
    case config::Recorder::ACCELERATION: return Kind::kAcceleration;
    default: return Kind::kDisplacement;
  }
}

// Adds a channel, or widens the one already asked for to keep the steps of both.
void add_channel(std::vector<RecordedChannel>& channels, RecordedChannel channel) {
  for (RecordedChannel& c : channels) {
    if (c.kind == channel.kind && c.dof == channel.dof && c.from_dof == channel.from_dof) {
      c.every = std::gcd(c.every, channel.every);
      return;
    }
  }
  channels.push_back(channel);
}

// The DOFs (0-based) a recorder's dofs and ranges name, in their order.
std::vector<int> recorder_dofs(const config::Recorder& r, int index, int dofs) {
  std::vector<int> out;
  for (int i = 0; i < r.dofs_size(); ++i)
    out.push_back(dof_within(r.dofs(i), dofs, field(index, "dofs[" + std::to_string(i) + "]")));
  for (int i = 0; i < r.ranges_size(); ++i) {
    const config::DofRange& range = r.ranges(i);
    const std::string where = field(index, "ranges[" + std::to_string(i) + "]");
    const int first = dof_within(range.first(), dofs, where + ".first");
    const int last = dof_within(range.last(), dofs, where + ".last");
    const int step = range.step() > 0 ? range.step() : 1;
    for (int dof = first; dof <= last; dof += step) out.push_back(dof);
  }
  return out;
}

void add_recorder(RecorderPlan& plan, const config::Recorder& r, int index, int dofs) {
  const int every = r.every() > 0 ? r.every() : 1;
  std::vector<Kind> kinds;
  for (int q : r.quantities()) kinds.push_back(quantity_kind(q));
  if (kinds.empty()) kinds.push_back(Kind::kDisplacement);
  for (int dof : recorder_dofs(r, index, dofs))
    for (Kind kind : kinds) add_channel(plan.channels, {kind, dof, -1, every});
  for (int i = 0; i < r.drifts_size(); ++i) {
    const std::string where = field(index, "drifts[" + std::to_string(i) + "]");
    const int upper = dof_within(r.drifts(i).dof(), dofs, where + ".dof");
    const int lower = r.drifts(i).from_dof() == 0
                          ? -1
                          : dof_within(r.drifts(i).from_dof(), dofs, where + ".from_dof");
    add_channel(plan.channels, {Kind::kDrift, upper, lower, every});
  }
  if (r.experimental()) add_channel(plan.channels, {Kind::kActuators, -1, -1, every});
  if (r.base_shear()) add_channel(plan.channels, {Kind::kBaseShear, -1, -1, every});
}

// The defaults (the header's rule) and, past kAllDofsLimit, their line.
// The DOFs first, then the actuators: the table every run wrote before recorders.
void add_defaults(RecorderPlan& plan, int dofs, const std::vector<int>& experimental_dofs) {
  if (dofs <= kAllDofsLimit) {
    for (int dof = 0; dof < dofs; ++dof)
      add_channel(plan.channels, {Kind::kDisplacement, dof, -1, 1});
    add_channel(plan.channels, {Kind::kActuators, -1, -1, 1});
    return;
  }
  std::set<int> chosen(experimental_dofs.begin(), experimental_dofs.end());
  for (int part : {0, 1, 2, 3}) chosen.insert(std::max(1, dofs * part / 4) - 1);
  chosen.insert(dofs - 1);
  std::ostringstream line;
  line << "recorders: none given; " << dofs << " DOFs, more than " << kAllDofsLimit
       << ", so each case keeps every actuator and the displacement of DOFs";
  const char* separator = " ";
  for (int dof : chosen) {
    add_channel(plan.channels, {Kind::kDisplacement, dof, -1, 1});
    line << separator << dof + 1;
    separator = ", ";
  }
  line << " (the experimental ones, 1, n/4, n/2, 3n/4 and the top); a recorders block keeps more";
  plan.defaults = line.str();
  add_channel(plan.channels, {Kind::kActuators, -1, -1, 1});
}

}  // namespace

bool RecorderPlan::keeps(std::size_t step) const {
  return std::any_of(channels.begin(), channels.end(),
                     [step](const RecordedChannel& c) { return c.keeps(step); });
}

std::size_t RecorderPlan::columns_per_case(std::size_t actuators) const {
  std::size_t columns = 0;
  for (const RecordedChannel& c : channels)
    columns += c.kind == Kind::kActuators ? 3 * actuators : 1;
  return columns;
}

core::SimulationOptions kept_by_recorders(const RecorderPlan& plan,
                                          const config::SafetyLimits& limits) {
  core::SimulationOptions options;
  options.kept_dofs = plan.kept_dofs;
  options.base_shear = plan.base_shear;
  options.peaks = limits.max_displacement() > 0 || limits.max_velocity() > 0;
  return options;
}

std::uint64_t run_bytes_per_step(const RecorderPlan& plan, int dofs, std::size_t actuators,
                                 std::size_t cases, bool peaks) {
  const std::uint64_t kept =
      plan.kept_dofs.empty() ? static_cast<std::uint64_t>(dofs) : plan.kept_dofs.size();
  const std::uint64_t simulation =
      8 + 24 * kept + 32 * actuators + (peaks ? 24 : 0) + (plan.base_shear ? 8 : 0);
  const std::uint64_t table = 8 * (2 + cases * plan.columns_per_case(actuators));
  return (cases + 1) * simulation + 8 * cases + table + 16;
}

void validate_recorders(const config::Study& study, const std::string& source) {
  for (int i = 0; i < study.recorders_size(); ++i) {
    const config::Recorder& r = study.recorders(i);
    require(
        r.dofs_size() + r.ranges_size() + r.drifts_size() > 0 || r.experimental() || r.base_shear(),
        source,
        field(i, "") +
            " asks for nothing: give dofs, ranges, drifts, experimental or "
            "base_shear");
    require(r.quantities().empty() || r.dofs_size() + r.ranges_size() > 0, source,
            field(i, "quantities") + " applies to dofs and ranges, and the recorder has none");
    require(
        r.every() >= 0, source,
        field(i, "every") + " must be >= 0 (0 means every step), got " + std::to_string(r.every()));
    for (int j = 0; j < r.dofs_size(); ++j)
      require(r.dofs(j) >= 1, source,
              field(i, "dofs[" + std::to_string(j) + "]") + " must be a DOF >= 1, got " +
                  std::to_string(r.dofs(j)));
    for (int j = 0; j < r.ranges_size(); ++j) {
      const config::DofRange& range = r.ranges(j);
      const std::string where = field(i, "ranges[" + std::to_string(j) + "]");
      require(range.first() >= 1 && range.last() >= range.first() && range.step() >= 0, source,
              where + " must have 1 <= first <= last and step >= 0, got first " +
                  std::to_string(range.first()) + ", last " + std::to_string(range.last()) +
                  ", step " + std::to_string(range.step()));
    }
    for (int j = 0; j < r.drifts_size(); ++j) {
      const config::Drift& drift = r.drifts(j);
      require(drift.dof() >= 1 && drift.from_dof() >= 0 && drift.dof() != drift.from_dof(), source,
              field(i, "drifts[" + std::to_string(j) + "]") +
                  " must join two different DOFs (dof >= 1, from_dof >= 0 with 0 the ground), "
                  "got dof " +
                  std::to_string(drift.dof()) + ", from_dof " + std::to_string(drift.from_dof()));
    }
  }
}

RecorderPlan plan_recorders(const config::Study& study, int dofs,
                            const std::vector<int>& experimental_dofs) {
  RecorderPlan plan;
  if (study.recorders().empty()) add_defaults(plan, dofs, experimental_dofs);
  for (int i = 0; i < study.recorders_size(); ++i) add_recorder(plan, study.recorders(i), i, dofs);
  for (const RecordedChannel& c : plan.channels)
    plan.base_shear = plan.base_shear || c.kind == Kind::kBaseShear;
  if (dofs <= kAllDofsLimit) return plan;
  std::set<int> kept(experimental_dofs.begin(), experimental_dofs.end());
  kept.insert(dofs - 1);
  for (const RecordedChannel& c : plan.channels) {
    if (c.dof >= 0) kept.insert(c.dof);
    if (c.from_dof >= 0) kept.insert(c.from_dof);
  }
  plan.kept_dofs.assign(kept.begin(), kept.end());
  return plan;
}

std::vector<int> experimental_dofs(const core::HybridPartition& partition) {
  std::set<int> out;
  const int dofs = partition.dofs();
  for (int s : partition.actuator_storeys) {
    if (s < dofs) {
      out.insert(s);
      if (!partition.by_dofs && s > 0) out.insert(s - 1);
      continue;
    }
    for (const auto& [dof, coefficient] :
         partition.elements.at(static_cast<std::size_t>(s - dofs)).terms)
      out.insert(dof);
  }
  return {out.begin(), out.end()};
}

}  // namespace rths::study
