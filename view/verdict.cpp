#include "view/verdict.h"

#include <fmt/format.h>

#include "core/number_text.h"

namespace rths::view {
namespace {

// The overruns of a run within the verdict, against the two limits it was judged by.
std::string overruns_within(const runtime::DeadlineCounts& c, const runtime::DeadlineRule& rule) {
  const double share =
      c.steps ? static_cast<double>(c.overruns) / static_cast<double>(c.steps) : 0.0;
  const std::string tolerance =
      rule.max_fraction < 0 ? "the overrun tolerance is off (max_overrun_fraction < 0)"
                            : fmt::format("within the tolerance of {:.3g} % (max_overrun_fraction)",
                                          100.0 * rule.max_fraction);
  return std::to_string(c.overruns) + " overruns in " + std::to_string(c.steps) + " steps (" +
         core::format_percent(share) + "), " + tolerance + "; worst streak " +
         std::to_string(c.worst_streak) + " steps, within the fail-safe's window of " +
         std::to_string(rule.max_streak) + "; each late step is marked in the record";
}

ShownVerdict not_ok(const runtime::RunFooter& footer) {
  const std::string& status = footer.status();
  if (status.rfind(runtime::kDeadlineMisses, 0) == 0)
    return {"failed", "failed", std::string(runtime::kDeadlineMisses), status};
  return {"stopped", "failed", footer.diverged() ? "diverged" : "stopped", status};
}

}  // namespace

ShownVerdict shown_verdict(const FinishedRun& run) {
  if (!run.footer.ok()) return not_ok(run.footer);
  const std::optional<std::string> missed =
      run.real_time ? runtime::deadline_verdict(run.counts, run.rule) : std::nullopt;
  if (missed) return {"failed", "failed", std::string(runtime::kDeadlineMisses), *missed};
  if (run.judged && run.judged->status.rfind("completed", 0) != 0)
    return {"completed", run.judged->fails ? "failed" : "warning", run.judged->status,
            run.judged->detail};
  if (run.real_time) {
    if (run.counts.overruns > 0)
      return {"completed", "warning",
              "completed with " + std::to_string(run.counts.overruns) + " overruns",
              overruns_within(run.counts, run.rule)};
  }
  if (run.platform_overridden)
    return {"completed", "warning", "completed on a refused platform",
            "the platform check refused this deployment and it ran anyway (--accept-platform): " +
                run.platform_verdict};
  return {"completed", "ok", "completed", ""};
}

}  // namespace rths::view
