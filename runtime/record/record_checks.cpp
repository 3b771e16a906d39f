#include "runtime/record/record_checks.h"

#include <cmath>

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

void check_header(const RecordContents& contents, RecordChecks& out) {
  std::size_t index = 0;
  while (index < contents.entries.size() && !contents.entries[index].has_header()) ++index;
  if (index == contents.entries.size()) {
    out.problems.push_back("no intact header entry");
    out.fatal = true;
    return;
  }
  const RunHeader& h = contents.entries[index].header();
  const std::string where = entry_name(index) + " (header): ";
  if (h.schema_version() != kSchemaVersion)
    out.problems.push_back(where + "schema version " + std::to_string(h.schema_version()) +
                           ", this reader knows " + std::to_string(kSchemaVersion));
  if (h.dofs() < 1 || h.dofs() > kMaxRecordDofs) {
    out.problems.push_back(where + "dofs " + std::to_string(h.dofs()) + " outside [1, " +
                           std::to_string(kMaxRecordDofs) + "]");
    out.fatal = true;
  } else if (h.actuators() < 0 || h.actuators() > h.dofs()) {
    out.problems.push_back(where + "actuators " + std::to_string(h.actuators()) +
                           " outside [0, dofs " + std::to_string(h.dofs()) + "]");
    out.fatal = true;
  }
}

// The first size or finiteness problem of one step's repeated field, or "".
template <class Values>
std::string field_problem(const char* name, const Values& values, int expected) {
  if (!values.empty() && values.size() != expected)
    return std::string(name) + " has " + std::to_string(values.size()) + " values, not " +
           std::to_string(expected);
  for (int i = 0; i < values.size(); ++i)
    if (!std::isfinite(values.Get(i)))
      return std::string(name) + "[" + std::to_string(i) + "] is not finite";
  return {};
}

std::string step_problem(const StepRecord& s, int dofs, int actuators) {
  if (!std::isfinite(s.time())) return "time is not finite";
  if (!std::isfinite(s.ground_acceleration())) return "ground_acceleration is not finite";
  for (const auto& [name, values, expected] :
       {std::tuple{"displacement", &s.displacement(), dofs},
        std::tuple{"velocity", &s.velocity(), dofs},
        std::tuple{"acceleration", &s.acceleration(), dofs},
        std::tuple{"command", &s.command(), actuators},
        std::tuple{"realised", &s.realised(), actuators},
        std::tuple{"measured_force", &s.measured_force(), actuators}}) {
    std::string problem = field_problem(name, *values, expected);
    if (!problem.empty()) return problem;
  }
  return {};
}

void check_steps(const RecordContents& contents, RecordChecks& out) {
  const RunHeader* header = contents.header();
  const int dofs = header && !out.fatal ? header->dofs() : 0;
  const int actuators = header && !out.fatal ? header->actuators() : 0;
  std::int64_t previous = -1;
  for (std::size_t i = 0; i < contents.entries.size(); ++i) {
    if (!contents.entries[i].has_step()) continue;
    const StepRecord& s = contents.entries[i].step();
    const std::string where = entry_name(i, &s) + ": ";
    if (previous < 0 && s.step() != 0 && !contents.lost_entries())
      out.problems.push_back(where + "the first step is not step 0");
    if (previous >= 0 && s.step() <= previous)
      out.problems.push_back(where + "comes after step " + std::to_string(previous) +
                             (s.step() == previous ? " (a duplicate)" : " (out of order)"));
    previous = std::max(previous, s.step());
    if (dofs == 0) continue;
    const std::string problem = step_problem(s, dofs, actuators);
    if (!problem.empty()) out.problems.push_back(where + problem);
  }
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
  check_header(contents, out);
  check_steps(contents, out);
  out.cut = contents.footer() == nullptr && !contents.truncated;
  return out;
}

}  // namespace rths::runtime
