#pragma once
// The one real-time verdict: whether a real-time run kept its deadlines well enough to be called
// a real-time test. The coordinator's outcome (and so its exit code and the record's footer),
// `rths identify`'s diagnosis (deadline_diagnosis.h), `rths launch`'s judgement of each record and
// the live view's badge all ask deadline_verdict(), on the same counts and the same rule, so no
// two of them can disagree about one record.
//
// Inputs  DeadlineCounts (a run's, or a record's):
//           steps         commanded steps: the record's rows less its initial state (step 0,
//                         never paced)
//           overruns      steps whose deadline had already passed when the loop came to wait for
//                         it (runtime::Pacer; StepRecord.overrun is the same flag)
//           worst_streak  the most consecutive overrun steps
//         DeadlineRule (deadline_rule(deployment, dt)):
//           max_fraction  deployment max_overrun_fraction (0 = 0.001), a fraction of the steps;
//                         < 0 turns off the fraction rule only
//           max_streak    the fail-safe's answer window in steps (answer_window_ms, or
//                         max_missed_answers; 3 by default): `rths rt-check` sizes it past this
//                         machine's stalls, so a clean run on a machine that passed the check
//                         stays within it (docs/realtime.md has the figures)
// Rules   the run fails its verdict on the first of these that holds:
//   dominated  overruns > kDominatedShare x steps: the response shows the platform as much as
//              the rig. Never turned off.
//   streak     worst_streak > max_streak: the integrator ran on stale forces, its commands late,
//              for longer than the fail-safe lets a node stay silent; the response is not a
//              real-time test's. Never turned off.
//   fraction   max_fraction >= 0 and overruns > max_fraction x steps.
// Output  the breach, and its text "completed with deadline misses: ..." naming the rule and the
//         figures; kNone / nothing when the run kept within all three or has no steps.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "rths/proto/deployment.pb.h"

namespace rths::runtime {

struct DeadlineCounts {
  std::uint64_t steps = 0, overruns = 0, worst_streak = 0;
};

struct DeadlineRule {
  double max_fraction = 0.001;   // of the steps; < 0: the fraction rule is off
  std::uint64_t max_streak = 3;  // steps
};

// How every deadline verdict's text begins (the servo loops' too, coordinator/deadline_verdict.h).
inline constexpr std::string_view kDeadlineMisses = "completed with deadline misses";

// More than half of the steps overrun: the record is dominated by them (identify says so too).
inline constexpr double kDominatedShare = 0.5;

enum class DeadlineBreach { kNone, kDominated, kStreak, kFraction };

// The deployment's rule at step dt (s): max_overrun_fraction and the answer window in steps.
DeadlineRule deadline_rule(const config::Deployment& deployment, double dt);

DeadlineBreach deadline_breach(const DeadlineCounts& counts, const DeadlineRule& rule);
std::optional<std::string> deadline_verdict(const DeadlineCounts& counts, const DeadlineRule& rule);

}  // namespace rths::runtime
