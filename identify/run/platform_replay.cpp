#include "identify/run/platform_replay.h"

#include <algorithm>
#include <numeric>
#include <sstream>

namespace rths::identify {
namespace {

std::vector<std::int64_t> own_answers(std::size_t steps) {
  std::vector<std::int64_t> used(steps);
  std::iota(used.begin(), used.end(), std::int64_t{0});
  return used;
}

// The rows of the sources `node` answers for.
std::vector<std::vector<std::int64_t>*> rows_of(const runtime::NodeSources& node,
                                                core::AnswerSchedule& schedule) {
  std::vector<std::vector<std::int64_t>*> out;
  auto& rows = node.numerical ? schedule.storey_used : schedule.actuator_used;
  for (int i : node.sources)
    if (i >= 0 && static_cast<std::size_t>(i) < rows.size())
      out.push_back(&rows[static_cast<std::size_t>(i)]);
  return out;
}

// The node of `id` among `nodes`, or nullptr.
const runtime::NodeSources* find_node(const std::vector<runtime::NodeSources>& nodes, int id) {
  for (const auto& node : nodes)
    if (node.node_id == id) return &node;
  return nullptr;
}

void drop_fresh_rows(core::AnswerSchedule& schedule, std::size_t steps) {
  const std::vector<std::int64_t> fresh = own_answers(steps);
  for (auto* rows : {&schedule.actuator_used, &schedule.storey_used})
    for (auto& row : *rows)
      if (row == fresh) row.clear();
}

void measure_ages(PlatformReplay& out) {
  double age_sum = 0.0;
  std::size_t aged = 0;
  for (const auto* rows : {&out.schedule.actuator_used, &out.schedule.storey_used})
    for (const auto& row : *rows)
      for (std::size_t k = 0; k < row.size(); ++k) {
        const std::int64_t age = static_cast<std::int64_t>(k) - row[k];
        if (age <= 0) continue;
        age_sum += static_cast<double>(age);
        ++aged;
        out.oldest = std::max(out.oldest, age);
      }
  out.mean_age = aged > 0 ? age_sum / static_cast<double>(aged) : 0.0;
  out.late_steps = out.schedule.late_steps();
}

}  // namespace

PlatformReplay platform_replay(const std::vector<const runtime::StepRecord*>& steps,
                               std::size_t count, const std::vector<runtime::NodeSources>& nodes,
                               int storeys, int actuators) {
  PlatformReplay out;
  out.steps = std::min(count, steps.size());
  auto& schedule = out.schedule;
  schedule.storey_used.assign(static_cast<std::size_t>(storeys), own_answers(out.steps));
  schedule.actuator_used.assign(static_cast<std::size_t>(actuators), own_answers(out.steps));
  for (std::size_t k = 1; k < out.steps; ++k)
    for (const runtime::LinkSample& link : steps[k]->links()) {
      const runtime::NodeSources* node = find_node(nodes, link.node_id());
      if (!node) continue;
      // An answer to a command not yet sent cannot have been used: the step's own then.
      const std::int64_t used =
          std::clamp<std::int64_t>(link.answered_step(), 0, static_cast<std::int64_t>(k));
      for (auto* row : rows_of(*node, schedule)) (*row)[k] = used;
    }
  drop_fresh_rows(schedule, out.steps);
  measure_ages(out);
  return out;
}

std::vector<std::int64_t> actuator_row(const core::AnswerSchedule& schedule, int a) {
  const auto i = static_cast<std::size_t>(a);
  return a >= 0 && i < schedule.actuator_used.size() ? schedule.actuator_used[i]
                                                     : std::vector<std::int64_t>{};
}

std::vector<double> aligned(const std::vector<std::int64_t>& used,
                            const std::vector<double>& recorded) {
  if (used.empty()) return recorded;
  const std::size_t n = std::min(used.size(), recorded.size());
  std::vector<double> out(n, 0.0);
  std::vector<bool> known(n, false);
  for (std::size_t k = 0; k < n; ++k) {
    const auto j = static_cast<std::size_t>(used[k]);
    if (j < n && !known[j]) {
      out[j] = recorded[k];
      known[j] = true;
    }
  }
  std::size_t last = n;  // the last known step so far; n: none yet
  for (std::size_t j = 0; j < n; ++j) {
    if (!known[j]) continue;
    if (last == n) std::fill(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(j), out[j]);
    for (std::size_t i = last + 1; last != n && i < j; ++i)
      out[i] = out[last] +
               (out[j] - out[last]) * static_cast<double>(i - last) / static_cast<double>(j - last);
    last = j;
  }
  if (last != n)
    std::fill(out.begin() + static_cast<std::ptrdiff_t>(last) + 1, out.end(), out[last]);
  return out;
}

std::string PlatformReplay::text() const {
  std::ostringstream out;
  out.precision(3);
  const double share =
      steps > 1 ? static_cast<double>(late_steps) / static_cast<double>(steps - 1) : 0.0;
  out << late_steps << " of " << (steps > 0 ? steps - 1 : 0) << " steps (" << 100.0 * share
      << " %) on an older answer: mean age " << mean_age << " steps, oldest " << oldest;
  return out.str();
}

}  // namespace rths::identify
