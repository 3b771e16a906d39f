#include "runtime/record/record_checks.h"

#include <fmt/format.h>
#include <google/protobuf/util/message_differencer.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <sstream>
#include <utility>

#include "runtime/node/schema.h"

namespace rths::runtime {

namespace {

std::string entry_name(std::size_t index, const StepRecord* step = nullptr) {
  std::string text = "entry ";
  text += std::to_string(index);
  if (step) {
    text += " (step ";
    text += std::to_string(step->step());
    text += ")";
  }
  return text;
}

// A problem found in one step: `kind` says which problems are the same (the same kind in
// consecutive steps is one region), `detail` names it in that step.
struct Finding {
  std::string kind, detail;
};

// Findings merged into regions of consecutive steps, each named once.
class Regions {
 public:
  // `ordinal`: the step's position among the record's steps (consecutive steps differ by one).
  void add(const Finding& f, std::size_t ordinal, std::size_t entry, std::int64_t step) {
    const auto open = open_.find(f.kind);
    if (open != open_.end() && regions_[open->second].last_ordinal + 1 == ordinal) {
      Region& r = regions_[open->second];
      r.last_ordinal = ordinal, r.last_entry = entry, r.last_step = step, ++r.count;
      return;
    }
    open_[f.kind] = regions_.size();
    regions_.push_back({f.detail, ordinal, entry, entry, step, step, 1});
  }
  // Appends one problem per region, in entry order.
  void name_into(std::vector<std::string>& problems) const {
    for (const Region& r : regions_) {
      if (r.count == 1) {
        problems.push_back("entry " + std::to_string(r.first_entry) + " (step " +
                           std::to_string(r.first_step) + "): " + r.detail);
        continue;
      }
      problems.push_back("entries " + std::to_string(r.first_entry) + "-" +
                         std::to_string(r.last_entry) + " (steps " + std::to_string(r.first_step) +
                         "-" + std::to_string(r.last_step) + ", " + std::to_string(r.count) +
                         " steps): " + r.detail + " (so at the first of them)");
    }
  }

 private:
  struct Region {
    std::string detail;  // the first step's
    std::size_t last_ordinal, first_entry, last_entry;
    std::int64_t first_step, last_step;
    std::size_t count;
  };
  std::vector<Region> regions_;
  std::map<std::string, std::size_t> open_;  // kind -> its latest region
};

// The bound a value is checked against, and what sets it.
struct Bound {
  double limit;
  std::string source;  // "the deployment's max_displacement", "a plausible"
};

struct Bounds {
  Bound u{kPlausibleDisplacement, "a plausible"}, v{kPlausibleVelocity, "a plausible"},
      a{kPlausibleAcceleration, "a plausible"}, drift{kPlausibleDisplacement, "a plausible"},
      force{kPlausibleForce, "a plausible"};
};

Bounds bounds_of(const RecordContents& contents) {
  Bounds b;
  const config::Study* study = contents.study_as_run();
  if (!study) return b;
  const config::SafetyLimits& limits = study->deployment().limits();
  if (limits.max_displacement() > 0) {
    b.u = {limits.max_displacement(), "the deployment's max_displacement"};
    b.drift = {2 * limits.max_displacement(), "twice the deployment's max_displacement"};
  }
  if (limits.max_velocity() > 0) b.v = {limits.max_velocity(), "the deployment's max_velocity"};
  return b;
}

// A damaged region lies before the first intact step (or anywhere, without one): the inputs entry,
// written after the header and before step 0, may have been in it.
bool inputs_may_be_lost(const RecordContents& contents) {
  std::uint64_t first_step = UINT64_MAX;
  for (std::size_t i = 0; i < contents.entries.size(); ++i)
    if (contents.entries[i].has_step()) {
      first_step = contents.offsets[i];
      break;
    }
  for (const RecordLoss& loss : contents.losses)
    if (loss.first_byte < first_step) return true;
  return contents.truncated && contents.truncated_at < first_step;
}

// The inputs entry is the one the header names (when it names one and the entry is intact).
void check_inputs(const RecordContents& contents, const RunHeader& h, RecordChecks& out) {
  if (h.inputs_crc32c() == 0 || !contents.checksummed) return;
  if (contents.inputs_crc32c == 0) {
    if (!inputs_may_be_lost(contents))
      out.problems.push_back(fmt::format(
          "no inputs entry: the header names one (CRC-32C {:x}) and no damaged region lies where "
          "it would be (before the first step): the record lost the inputs it was run with",
          h.inputs_crc32c()));
    return;
  }
  if (contents.inputs_crc32c == h.inputs_crc32c()) return;
  std::size_t index = 0;
  while (!contents.entries[index].has_inputs()) ++index;
  std::ostringstream text;
  text << entry_name(index) << " (inputs): its CRC-32C " << std::hex << contents.inputs_crc32c
       << " is not the header's inputs_crc32c " << h.inputs_crc32c()
       << " (inputs that are not the run's)";
  out.problems.push_back(text.str());
}

// The first entry of the header's recorded_dofs that is not a DOF of the model above the entry
// before it (they name each StepRecord column's DOF, ascending); nullopt when all are.
std::optional<int> unordered_recorded_dof(const RunHeader& h) {
  for (int i = 0; i < h.recorded_dofs_size(); ++i) {
    const int dof = h.recorded_dofs(i);
    if (dof < 0 || dof >= h.dofs() || (i > 0 && dof <= h.recorded_dofs(i - 1))) return i;
  }
  return std::nullopt;
}

// The first intact header (or the one assumed from the steps) is sound; its entry index, or
// contents.entries.size() for an assumed one.
std::size_t check_header(const RecordContents& contents, RecordChecks& out) {
  std::size_t index = 0;
  while (index < contents.entries.size() && !contents.entries[index].has_header()) ++index;
  const RunHeader* h = contents.header_or_assumed();
  if (!h) {
    out.problems.push_back("no intact header entry");
    out.fatal = true;
    return index;
  }
  const bool assumed = index == contents.entries.size();
  if (assumed) out.problems.push_back("no intact header entry: " + contents.assumed);
  const std::string where = assumed ? "the assumed header: " : entry_name(index) + " (header): ";
  if (h->schema_version() != kSchemaVersion)
    out.problems.push_back(where + "schema version " + std::to_string(h->schema_version()) +
                           ", this reader knows " + std::to_string(kSchemaVersion));
  if (!(std::isfinite(h->dt()) && h->dt() > 0))
    out.problems.push_back(where + "dt " + fmt::format("{:g}", h->dt()) +
                           " s is not a time step (finite, > 0)");
  if (h->dofs() < 1 || h->dofs() > kMaxRecordDofs) {
    out.problems.push_back(where + "dofs " + std::to_string(h->dofs()) + " outside [1, " +
                           std::to_string(kMaxRecordDofs) + "]");
    out.fatal = true;
  } else if (h->actuators() < 0 || h->actuators() > h->dofs()) {
    out.problems.push_back(where + "actuators " + std::to_string(h->actuators()) +
                           " outside [0, dofs " + std::to_string(h->dofs()) + "]");
    out.fatal = true;
  } else if (const auto bad = unordered_recorded_dof(*h)) {
    out.problems.push_back(where + "recorded_dofs[" + std::to_string(*bad) + "] " +
                           std::to_string(h->recorded_dofs(*bad)) + " is not a DOF of 0.." +
                           std::to_string(h->dofs() - 1) + " above the one before it");
    out.fatal = true;
  }
  check_inputs(contents, *h, out);
  return index;
}

// Every later header copy says what the first intact one says.
void check_copies(const RecordContents& contents, std::size_t first, RecordChecks& out) {
  if (first >= contents.entries.size()) return;
  const RunHeader& reference = contents.entries[first].header();
  for (std::size_t i = first + 1; i < contents.entries.size(); ++i) {
    if (!contents.entries[i].has_header()) continue;
    google::protobuf::util::MessageDifferencer differ;
    std::string differences;
    differ.ReportDifferencesToString(&differences);
    if (differ.Compare(reference, contents.entries[i].header())) continue;
    if (differences.size() > 300) differences = differences.substr(0, 300) + "...";
    while (!differences.empty() && differences.back() == '\n') differences.pop_back();
    for (char& c : differences)
      if (c == '\n') c = ';';
    out.problems.push_back(entry_name(i) + " (header copy): disagrees with the header in " +
                           entry_name(first) + ": " + differences);
  }
}

}  // namespace

namespace {

// A repeated field sized as the header says, each value finite and within its bound (the first
// value that is not is named).
template <class Values>
void check_field(const std::string& name, const Values& values, int expected, const Bound& bound,
                 const char* unit, std::vector<Finding>& out) {
  if (!values.empty() && values.size() != expected) {
    out.push_back({name + " size", name + " has " + std::to_string(values.size()) +
                                       " values, not " + std::to_string(expected)});
    return;
  }
  for (int i = 0; i < values.size(); ++i) {
    const double x = values.Get(i);
    const std::string at = name + "[" + std::to_string(i) + "]";
    if (!std::isfinite(x)) {
      out.push_back({name + " finite", at + " is not finite"});
      return;
    }
    if (std::abs(x) > bound.limit) {
      out.push_back({name + " bound", at + " = " + fmt::format("{:g}", x) + " " + unit +
                                          " is beyond " + bound.source + " " +
                                          fmt::format("{:g}", bound.limit) + " " + unit});
      return;
    }
  }
}

std::vector<Finding> value_findings(const StepRecord& s, int dofs, int actuators, const Bounds& b) {
  std::vector<Finding> out;
  const double ground = s.ground_acceleration();
  if (!std::isfinite(ground))
    out.push_back({"ground finite", "ground_acceleration is not finite"});
  else if (std::abs(ground) > kPlausibleAcceleration)
    out.push_back({"ground bound", "ground_acceleration = " + fmt::format("{:g}", ground) +
                                       " m/s^2 is beyond a plausible " +
                                       fmt::format("{:g}", kPlausibleAcceleration) + " m/s^2"});
  check_field("displacement", s.displacement(), dofs, b.u, "m", out);
  check_field("velocity", s.velocity(), dofs, b.v, "m/s", out);
  check_field("acceleration", s.acceleration(), dofs, b.a, "m/s^2", out);
  check_field("command", s.command(), actuators, b.drift, "m", out);
  check_field("realised", s.realised(), actuators, b.drift, "m", out);
  check_field("measured_force", s.measured_force(), actuators, b.force, "N", out);
  return out;
}

// One lag of a link sample: finite, and not negative when `signed_ok` is false.
void check_lag(const std::string& kind, const std::string& at, const char* name, double value,
               bool signed_ok, std::vector<Finding>& out) {
  if (!std::isfinite(value))
    out.push_back({kind + name + " finite", fmt::format("{}{} is not finite", at, name)});
  else if (!signed_ok && value < 0)
    out.push_back({kind + name + " negative",
                   fmt::format("{}{} {:g} s is negative (a lag or a time span)", at, name, value)});
}

// Each link sample in its range: the answered step neither negative nor after the step that
// records it (an answer from the future); every lag finite; the spans one clock measures
// (injected lag, round trip, the controller's round trip) not negative. One-way lags may be
// negative across hosts (they carry the hosts' clock offset): finite only.
std::vector<Finding> link_findings(const StepRecord& s) {
  std::vector<Finding> out;
  for (int j = 0; j < s.links_size(); ++j) {
    const LinkSample& link = s.links(j);
    const std::string kind = fmt::format("link {} ", link.node_id());
    const std::string at = fmt::format("links[{}] (node {}): ", j, link.node_id());
    if (link.answered_step() < 0 || link.answered_step() > s.step())
      out.push_back(
          {kind + "answered", fmt::format("{}answered_step {} {}", at, link.answered_step(),
                                          link.answered_step() < 0
                                              ? "is negative"
                                              : "is after this step (an answer from the future)")});
    check_lag(kind, at, "injected_lag", link.injected_lag(), false, out);
    check_lag(kind, at, "round_trip", link.round_trip(), false, out);
    check_lag(kind, at, "one_way_down", link.one_way_down(), true, out);
    check_lag(kind, at, "one_way_up", link.one_way_up(), true, out);
    check_lag(kind, at, "controller_round_trip", link.controller_round_trip(), false, out);
    for (int a = 0; a < link.prediction_error_size(); ++a)
      if (!std::isfinite(link.prediction_error(a)))
        out.push_back({kind + "prediction finite",
                       fmt::format("{}prediction_error[{}] is not finite", at, a)});
  }
  return out;
}

// The step's timing: lateness and command latency finite (either sign: early, or no command
// written this step), the step's wall time finite and not negative.
std::vector<Finding> timing_findings(const StepRecord& s) {
  std::vector<Finding> out;
  if (!std::isfinite(s.lateness())) out.push_back({"lateness", "lateness is not finite"});
  if (!std::isfinite(s.command_latency()))
    out.push_back({"command latency", "command_latency is not finite"});
  if (!(std::isfinite(s.step_wall()) && s.step_wall() >= 0))
    out.push_back({"step wall", fmt::format("step_wall {:g} s is not a time span (finite, >= 0)",
                                            s.step_wall())});
  return out;
}

// The intact steps read so far: the highest step number, and the last step's time and entry.
struct Sequence {
  bool any = false;
  std::int64_t highest = -1;
  double time = 0;
  std::size_t entry = 0;
};

// A damaged region lies between entries `a` and `b` (it may have held the steps between them).
bool loss_between(const RecordContents& c, std::size_t a, std::size_t b) {
  for (const RecordLoss& loss : c.losses)
    if (loss.first_byte > c.offsets[a] && loss.first_byte < c.offsets[b]) return true;
  return false;
}

// Where the step at entry `i` stands in the sequence and in time (dt 0: the header's dt is no
// step, and time is checked for order only).
std::vector<Finding> sequence_findings(const RecordContents& c, std::size_t i, const StepRecord& s,
                                       const Sequence& before, double dt) {
  std::vector<Finding> out;
  const std::int64_t k = s.step();
  if (!before.any) {
    if (k != 0 && !c.lost_entries()) out.push_back({"first", "the first step is not step 0"});
  } else if (k <= before.highest) {
    out.push_back({"order", "comes after step " + std::to_string(before.highest) +
                                (k == before.highest ? " (a duplicate)" : " (out of order)")});
  } else if (k > before.highest + 1 && !loss_between(c, before.entry, i)) {
    out.push_back({"gap", "steps " + std::to_string(before.highest + 1) + "-" +
                              std::to_string(k - 1) +
                              " are absent before it with no damaged region where they would "
                              "be (a gap in the sequence)"});
  }
  if (!std::isfinite(s.time())) {
    out.push_back({"time finite", "time is not finite"});
    return out;
  }
  if (before.any && s.time() < before.time)
    out.push_back({"time back", "time " + fmt::format("{:g}", s.time()) +
                                    " s is before the step before's " +
                                    fmt::format("{:g}", before.time) + " s (time goes back)"});
  const double expected = static_cast<double>(k) * dt;
  if (dt > 0 && !(std::abs(s.time() - expected) <= dt / 2))
    out.push_back({"time dt", "time " + fmt::format("{:g}", s.time()) + " s is not step x dt (" +
                                  std::to_string(k) + " x " + fmt::format("{:g}", dt) +
                                  " s = " + fmt::format("{:g}", expected) + " s)"});
  return out;
}

void check_steps(const RecordContents& contents, RecordChecks& out) {
  const RunHeader* header = contents.header_or_assumed();
  const int dofs = header && !out.fatal ? recorded_columns(*header) : 0;
  const int actuators = header && !out.fatal ? header->actuators() : 0;
  const double dt = header && std::isfinite(header->dt()) && header->dt() > 0 ? header->dt() : 0;
  const Bounds bounds = bounds_of(contents);
  Regions regions;
  Sequence before;
  std::size_t ordinal = 0;
  for (std::size_t i = 0; i < contents.entries.size(); ++i) {
    if (!contents.entries[i].has_step()) continue;
    const StepRecord& s = contents.entries[i].step();
    for (const Finding& f : sequence_findings(contents, i, s, before, dt))
      regions.add(f, ordinal, i, s.step());
    if (dofs > 0)
      for (const Finding& f : value_findings(s, dofs, actuators, bounds))
        regions.add(f, ordinal, i, s.step());
    for (const Finding& f : link_findings(s)) regions.add(f, ordinal, i, s.step());
    for (const Finding& f : timing_findings(s)) regions.add(f, ordinal, i, s.step());
    before = {true, std::max(before.highest, s.step()), s.time(), i};
    ++ordinal;
  }
  regions.name_into(out.problems);
}

// A damaged region, or the cut of a truncated record, lies within [from, to) of the file.
bool damage_within(const RecordContents& c, std::uint64_t from, std::uint64_t to) {
  for (const RecordLoss& loss : c.losses)
    if (loss.end_byte > from && loss.first_byte < to) return true;
  return c.truncated && c.truncated_at >= from && c.truncated_at < to;
}

// The footer's count against the steps: it counts the exchanges, so the run recorded steps 0 to
// that count. Steps after the highest intact one up to the count with no damaged region where
// they would be (between that step and the footer) were lost without a trace; steps beyond the
// count are steps the run did not make.
void check_footer(const RecordContents& c, RecordChecks& out) {
  std::size_t at = 0;
  while (at < c.entries.size() && !c.entries[at].has_footer()) ++at;
  if (at == c.entries.size() || !c.entries[at].footer().has_counters()) return;
  const std::uint64_t counted = c.entries[at].footer().counters().steps();
  const auto last = static_cast<std::int64_t>(std::min<std::uint64_t>(counted, INT64_MAX - 1));
  std::int64_t highest = -1;
  std::uint64_t after = 0;  // the byte after which the missing steps would lie
  for (std::size_t i = 0; i < c.entries.size(); ++i)
    if (c.entries[i].has_step() && c.entries[i].step().step() > highest)
      highest = c.entries[i].step().step(), after = c.offsets[i] + 1;
  const std::string where =
      fmt::format("{} (footer): counts {} exchanges (steps 0-{})", entry_name(at), counted, last);
  if (highest > last)
    out.problems.push_back(
        fmt::format("{} but the record holds step {}: steps the run did not "
                    "make",
                    where, highest));
  else if (highest < last && !damage_within(c, after, c.offsets[at]))
    out.problems.push_back(fmt::format(
        "{} and the last intact step is {}: steps {}-{} are absent with no damaged region where "
        "they would be (lost steps)",
        where, highest, highest + 1, last));
}

}  // namespace

std::string RecordChecks::summary(std::size_t shown) const {
  std::string text =
      std::to_string(problems.size()) + (problems.size() == 1 ? " problem" : " problems");
  for (std::size_t i = 0; i < problems.size() && i < shown; ++i) {
    text += i == 0 ? ": " : "; ";
    text += problems[i];
  }
  if (problems.size() > shown) {
    text += "; and ";
    text += std::to_string(problems.size() - shown);
    text += " more";
  }
  if (cut) text += "; no footer: the record stops between two entries (the run was cut short)";
  return text;
}

RecordChecks check_record(const RecordContents& contents) {
  RecordChecks out;
  check_copies(contents, check_header(contents, out), out);
  check_steps(contents, out);
  check_footer(contents, out);
  out.cut = contents.footer() == nullptr && !contents.truncated;
  return out;
}

}  // namespace rths::runtime
