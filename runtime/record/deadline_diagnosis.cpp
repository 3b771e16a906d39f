#include "runtime/record/deadline_diagnosis.h"

#include <algorithm>
#include <sstream>

#include "core/metrics.h"
#include "core/number_text.h"
#include "core/time_text.h"

namespace rths::runtime {
namespace {

std::vector<std::string> advice_for(const DeadlineDiagnosis& d) {
  if (d.stall_overruns >= d.work_overruns) {
    return {
        "measure the machine first: `rths rt-check CONFIG` reports its stalls and the fail-safe "
        "and max_overrun_fraction it can keep",
        "run nothing else on the machine during the test; `pin_loop: true loop_cpu: N` gives the "
        "loop a CPU of its own (and isolcpus / a PREEMPT_RT kernel on a lab machine)",
        "`wait_policy: WAIT_SLEEP_THEN_SPIN` wakes the loop early and spins to the deadline",
        "if the stalls are what this machine does, accept them knowingly: raise "
        "max_overrun_fraction (the record keeps every late step)"};
  }
  return {
      "the step itself is too slow for dt: lower the rate (a larger dt) or host fewer nodes "
      "in series",
      "keep the nodes off the loop's CPU (`pin_loop: true loop_cpu: N`)",
      "a node whose link injects a long lag is not waited for; check the slowest node's log"};
}

// The record's worth, first by how many steps overran, then by the longest run of them; the
// verdict's breach decides the two that say it is no real-time test's.
std::string usability_of(const DeadlineDiagnosis& d, const DeadlineRule& rule) {
  const double share = d.overrun_share();
  const std::uint64_t streak_window = rule.max_streak;
  const DeadlineBreach breach = deadline_breach(d.counts(), rule);
  if (breach == DeadlineBreach::kDominated)
    return "dominated by overruns: " + core::format_percent(share) +
           " of the steps overran, so the response shows the platform as much as the rig; the "
           "lag measurements stand, the response and what is identified from it do not stand for "
           "a real-time test";
  if (breach == DeadlineBreach::kStreak)
    return "use with care: " + std::to_string(d.worst_streak) +
           " steps in a row overran, so the integrator used stale forces that long; "
           "the lag measurements stand, the response is not a real-time test's";
  if (share > DeadlineDiagnosis::kUsableShare)
    return "use with care: " + core::format_percent(share) +
           " of the steps overran (isolated, worst streak " + std::to_string(d.worst_streak) +
           "); every force is tied to the step it answers, but the response carries that many "
           "late steps";
  return "usable as recorded: the overruns were isolated (worst streak " +
         std::to_string(d.worst_streak) + " steps, within the fail-safe's " +
         std::to_string(streak_window) + "), " + core::format_percent(share) +
         " of the steps, every force is tied to the step it answers and the late steps are marked";
}

}  // namespace

DeadlineCounts DeadlineDiagnosis::counts() const { return {steps, overruns, worst_streak}; }

double DeadlineDiagnosis::overrun_share() const {
  return steps ? static_cast<double>(overruns) / static_cast<double>(steps) : 0.0;
}

bool needs_deadline_diagnosis(const std::string& status, std::uint64_t overruns) {
  return status.find("deadline misses") != std::string::npos ||
         (overruns > 0 && status != "completed");
}

DeadlineDiagnosis diagnose_deadlines(const std::vector<const StepRecord*>& steps, double dt,
                                     const DeadlineRule& rule) {
  DeadlineDiagnosis d;
  d.period = dt;
  // The first row is the initial state, never paced: the coordinator judges the steps after it.
  d.steps = steps.empty() ? 0 : steps.size() - 1;
  std::vector<double> walls;
  walls.reserve(steps.size());
  std::uint64_t streak = 0;
  for (const StepRecord* s : steps) {
    walls.push_back(s->step_wall());
    streak = s->overrun() ? streak + 1 : 0;
    d.worst_streak = std::max(d.worst_streak, streak);
    if (!s->overrun()) continue;
    ++d.overruns;
    d.worst_lateness = std::max(d.worst_lateness, s->lateness());
    ++(s->step_wall() > dt ? d.work_overruns : d.stall_overruns);
  }
  if (!walls.empty()) {
    std::sort(walls.begin(), walls.end());
    d.step_wall_median = core::median(walls);
    d.step_wall_p99 = walls[std::min(walls.size() - 1, walls.size() * 99 / 100)];
  }
  d.verdict = deadline_verdict(d.counts(), rule);
  if (d.overruns == 0) {
    d.cause = "none";
    d.usability = "every step kept its deadline";
    return d;
  }
  d.cause = d.stall_overruns >= d.work_overruns ? "platform stalls" : "the loop's own work";
  d.advice = advice_for(d);
  d.usability = usability_of(d, rule);
  return d;
}

std::optional<DeadlineDiagnosis> diagnose_record_deadlines(const RecordContents& record) {
  const RunHeader* header = record.header();
  if (header == nullptr || header->study().deployment().clock() != config::Deployment::REAL_TIME)
    return std::nullopt;
  return diagnose_deadlines(record.steps(), header->dt(),
                            deadline_rule(header->study().deployment(), header->dt()));
}

std::string DeadlineDiagnosis::describe() const {
  std::ostringstream out;
  out << "deadline misses: " << overruns << " of " << steps << " steps; cause: " << cause << " ("
      << stall_overruns << " with the step's work inside the " << core::format_ms(period)
      << " period, so the wake-up "
      << "came late; " << work_overruns << " whose own work overran; step work median "
      << core::format_ms(step_wall_median) << ", p99 " << core::format_ms(step_wall_p99)
      << "; worst lateness " << core::format_ms(worst_lateness) << ")\n";
  for (const std::string& a : advice) out << "  to do: " << a << "\n";
  out << "  the record: " << usability << "\n";
  return out.str();
}

}  // namespace rths::runtime
