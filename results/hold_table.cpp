// hold_table (results/results.h): the controller nodes' holds, frame by frame.
#include <algorithm>
#include <cmath>
#include <limits>

#include "results/results.h"

namespace rths::results {
namespace {

constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();

const char* kind_text(runtime::HoldEntry::Kind kind) {
  switch (kind) {
    case runtime::HoldEntry::SENT_HOLD: return "sent HOLD";
    case runtime::HoldEntry::ANSWER: return "answer";
    case runtime::HoldEntry::SENT_STOP: return "sent STOP";
    default: return "unknown";
  }
}

// Values of entry field `field` (position or force), actuator `a`; NaN where an entry has none.
template <class Field>
std::vector<double> per_actuator(const std::vector<const runtime::HoldEntry*>& rows, int a,
                                 Field field) {
  std::vector<double> out;
  out.reserve(rows.size());
  for (const runtime::HoldEntry* e : rows) {
    const auto& values = field(*e);
    out.push_back(a < values.size() ? values.Get(a) : kMissing);
  }
  return out;
}

}  // namespace

Table hold_table(const runtime::RunFooter& footer) {
  std::vector<const runtime::HoldEntry*> rows;
  std::vector<double> node, entry, time, frame, status;
  std::vector<std::string> kind, verdict;
  int actuators = 0;
  for (const runtime::NodeRejects& n : footer.node_rejects())
    for (const runtime::HoldEntry& e : n.controller().hold_log()) {
      rows.push_back(&e);
      node.push_back(n.node_id());
      entry.push_back(static_cast<double>(e.kind()) - 1.0);
      kind.emplace_back(kind_text(e.kind()));
      time.push_back(e.time());
      frame.push_back(static_cast<double>(e.counter()));
      status.push_back(static_cast<double>(e.status()));
      verdict.push_back(e.verdict());
      actuators = std::max({actuators, e.position_size(), e.force_size()});
    }
  Table t;
  t.add_numbers("node", "", std::move(node));
  t.add_numbers("entry", "", std::move(entry));
  t.add_texts("kind", "", std::move(kind));
  t.add_numbers("time_s", "s", std::move(time));
  t.add_numbers("frame", "", std::move(frame));
  t.add_numbers("status", "", std::move(status));
  for (int a = 0; a < actuators; ++a) {
    const std::string j = std::to_string(a + 1);
    t.add_numbers(
        "position" + j + "_m", "m",
        per_actuator(
            rows, a, [](const runtime::HoldEntry& e) -> const auto& { return e.position(); }));
    t.add_numbers(
        "force" + j + "_N", "N",
        per_actuator(
            rows, a, [](const runtime::HoldEntry& e) -> const auto& { return e.force(); }));
  }
  t.add_texts("verdict", "", std::move(verdict));
  return t;
}

}  // namespace rths::results
