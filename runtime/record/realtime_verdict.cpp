#include "runtime/record/realtime_verdict.h"

#include "runtime/node/plan.h"

namespace rths::runtime {
namespace {

bool beyond(std::uint64_t part, std::uint64_t whole, double fraction) {
  return static_cast<double>(part) > fraction * static_cast<double>(whole);
}

// "N overruns in S steps" and "P %" (the share), as the coordinator has always written them.
std::string overruns_in_steps(const DeadlineCounts& c) {
  return std::to_string(c.overruns) + " overruns in " + std::to_string(c.steps) + " steps";
}
std::string share(const DeadlineCounts& c) {
  return std::to_string(100.0 * static_cast<double>(c.overruns) / static_cast<double>(c.steps)) +
         " %";
}

}  // namespace

DeadlineRule deadline_rule(const config::Deployment& deployment, double dt) {
  DeadlineRule rule;
  rule.max_fraction = max_overrun_fraction(deployment);
  rule.max_streak = static_cast<std::uint64_t>(max_missed_answers(deployment, dt));
  return rule;
}

DeadlineBreach deadline_breach(const DeadlineCounts& c, const DeadlineRule& rule) {
  if (c.steps == 0) return DeadlineBreach::kNone;
  if (beyond(c.overruns, c.steps, kDominatedShare)) return DeadlineBreach::kDominated;
  if (c.worst_streak > rule.max_streak) return DeadlineBreach::kStreak;
  if (rule.max_fraction >= 0 && beyond(c.overruns, c.steps, rule.max_fraction))
    return DeadlineBreach::kFraction;
  return DeadlineBreach::kNone;
}

std::optional<std::string> deadline_verdict(const DeadlineCounts& c, const DeadlineRule& rule) {
  const std::string head = std::string(kDeadlineMisses) + ": ";
  switch (deadline_breach(c, rule)) {
    case DeadlineBreach::kNone: return std::nullopt;
    case DeadlineBreach::kDominated:
      return head + overruns_in_steps(c) + " (" + share(c) + ", more than half; worst streak " +
             std::to_string(c.worst_streak) +
             "): the response shows the platform as much as the rig, it is not a real-time test's";
    case DeadlineBreach::kStreak:
      return head + std::to_string(c.worst_streak) +
             " steps in a row overran, more than the fail-safe's window of " +
             std::to_string(rule.max_streak) + " (" + overruns_in_steps(c) + ", " + share(c) +
             "): the integrator used stale forces that long, the response is not a real-time "
             "test's";
    case DeadlineBreach::kFraction:
      return head + overruns_in_steps(c) + " (" + share(c) + ", tolerance " +
             std::to_string(100.0 * rule.max_fraction) + " %; worst streak " +
             std::to_string(c.worst_streak) + ")";
  }
  return std::nullopt;
}

}  // namespace rths::runtime
