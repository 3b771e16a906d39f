#pragma once
// What the view's badge says of a run that ended: its state, the few words on the badge, how
// loudly (the page's colour) and the whole verdict beneath it, in the words the coordinator and
// `rths launch` use for the same record.
//
// Input  FinishedRun: the record's footer (ok, status, failed node), its clock, the deadline
//        counts of its rows and the rule of its deployment (runtime::deadline_rule), whether
//        its platform check was refused and run anyway (--accept-platform), and, when `rths
//        launch` serves the record after the run, how it judged the case against the lag-free
//        run (JudgedCase).
// Rules, the first that holds:
//   footer not ok      "failed"; badge "completed with deadline misses" when its status begins
//                      so (the loop's or a servo's), "diverged" for a diverged run, else
//                      "stopped" (state "stopped"); the text is the status (the failed node
//                      is the footer's, shown beside it).
//   verdict breached   a real-time run whose footer is ok but whose rows fail the one real-time
//                      verdict (runtime::deadline_verdict; a record of an older coordinator):
//                      "failed", badge "completed with deadline misses", the verdict as text.
//   judged otherwise   `rths launch` judged the case other than "completed" ("diverging",
//                      "diverged (expected)", "limit tripped", ...: its summary table's status):
//                      that status on the badge, the text why; "failed" when launch fails on
//                      it, "warning" when it does not (expect_unstable, --allow-unstable).
//   overruns           a real-time run within the verdict that overran at all: "warning", badge
//                      "completed with N overruns", the text their share against the tolerance
//                      and the worst streak against the fail-safe's window: a test that kept its
//                      deadlines well enough, which a reader should still know of.
//   platform refused   "warning", badge "completed on a refused platform", the check's verdict.
//   otherwise          "ok", badge "completed", no text.
// state is what the feed's status has always carried: "failed", "stopped" or "completed".

#include <optional>
#include <string>

#include "runtime/record/realtime_verdict.h"
#include "runtime/record/record.h"

namespace rths::view {

// How `rths launch` judged a case from its record (analysis::CaseOutcome): its status as its
// summary table shows it, why, and whether launch exits non-zero for it.
struct JudgedCase {
  std::string status = "completed";
  std::string detail;
  bool fails = false;
};

struct FinishedRun {
  runtime::RunFooter footer;
  bool real_time = false;
  runtime::DeadlineCounts counts;  // steps: the commanded rows (less step 0)
  runtime::DeadlineRule rule;
  bool platform_overridden = false;
  std::string platform_verdict;  // the check's words, when overridden
  std::optional<JudgedCase> judged;
};

struct ShownVerdict {
  std::string state;  // "completed", "failed", "stopped"
  std::string level;  // "ok", "warning", "failed": the badge's colour
  std::string badge;
  std::string text;  // empty for a plain "completed"
};

ShownVerdict shown_verdict(const FinishedRun& run);

}  // namespace rths::view
