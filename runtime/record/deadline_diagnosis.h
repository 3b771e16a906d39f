#pragma once
// Why a real-time run missed its deadlines, read from its record, and what to do about it.
//
// Input: the record's steps (StepRecord.overrun, lateness = step end - deadline (s), step_wall =
// the step's own exchange + integration (s)) and the period dt (s).
// Each overrun step is put down to one cause:
//   the loop's own work   step_wall > dt: the step's exchange and integration alone took longer
//                         than its period (too many nodes in series, a slow node, a rate too high)
//   a platform stall      otherwise: the work fitted, so the wake-up came late (the kernel or the
//                         hypervisor did not run the loop on time: other load, a VM's steal)
// The diagnosis names the larger share, the settings that address it, and what the record is still
// good for: a run whose overruns were isolated (worst streak within the fail-safe's window) kept
// every answer's step and lag, so its response and lag measurements stand as recorded, with the
// late steps marked; a run with long streaks used stale forces for many steps in a row.
// Whether the run passes as a real-time test is the one verdict (realtime_verdict.h) on the
// record's counts: `verdict`, and "not a real-time test" in `usability` exactly when that verdict
// names a dominating share or a streak.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "runtime/record/realtime_verdict.h"
#include "runtime/record/record.h"

namespace rths::runtime {

struct DeadlineDiagnosis {
  // A record is usable as recorded only when at most kUsableShare of its steps overran (and no
  // streak outlasted the fail-safe's window); past kDominatedShare the overruns dominate it.
  static constexpr double kUsableShare = 0.1, kDominatedShare = runtime::kDominatedShare;
  std::uint64_t steps = 0;                             // commanded: the rows less step 0
  std::uint64_t overruns = 0;                          // rows flagged overrun
  std::uint64_t work_overruns = 0;                     // step_wall > dt
  std::uint64_t stall_overruns = 0;                    // the rest
  std::uint64_t worst_streak = 0;                      // most consecutive overrun steps
  double period = 0.0;                                 // s
  double step_wall_median = 0.0, step_wall_p99 = 0.0;  // s, over every step
  double worst_lateness = 0.0;                         // s
  std::string cause;                   // "platform stalls", "the loop's own work", "none"
  std::vector<std::string> advice;     // settings that would help, most useful first
  std::string usability;               // what the record is still good for
  std::optional<std::string> verdict;  // deadline_verdict() of the counts; nothing: passed
  DeadlineCounts counts() const;
  double overrun_share() const;  // overruns / steps, 0 without steps
  // Several lines for a summary: the cause with its figures, the advice, the usability.
  std::string describe() const;
};

// Whether a run's end calls for the diagnosis: its status names deadline misses, or it did not
// complete after overruns (a fail-safe stop when stalls outlast the answer window is one).
bool needs_deadline_diagnosis(const std::string& status, std::uint64_t overruns);

// `rule`: the run's deadline_rule(deployment, dt); a run whose worst streak stays within its
// max_streak (the fail-safe's window) is called usable with the late steps marked.
DeadlineDiagnosis diagnose_deadlines(const std::vector<const StepRecord*>& steps, double dt,
                                     const DeadlineRule& rule);

// A real-time record's diagnosis under its own deployment (the header's study) and dt, as
// `rths identify` and `rths launch` read it; nothing for a lockstep record or one without a
// header.
std::optional<DeadlineDiagnosis> diagnose_record_deadlines(const RecordContents& record);

}  // namespace rths::runtime
