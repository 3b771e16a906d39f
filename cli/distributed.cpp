#include "cli/distributed.h"

#include <string>

#include "cli/commands.h"
#include "cli/support.h"

namespace rths::cli {
namespace {

// A coordinator that ran and failed, or that was killed (128 + signal) or stopped at the
// launcher's timeout (124), failed the run; 2 and 3 are its own bad input and environment.
int exit_code_of(int coordinator_exit) {
  switch (coordinator_exit) {
    case 0: return kExitOk;
    case 1: return kExitRunFailed;
    case 2: return kExitBadInput;
    case 3: return kExitEnvironment;
    default: return coordinator_exit >= 124 ? kExitRunFailed : kExitEnvironment;
  }
}

}  // namespace

void fail_if_distributed_failed(const DistributedResults& results,
                                const std::vector<DistributedRun>& runs, bool allow_unstable) {
  for (const DistributedRun& run : runs) {
    if (run.coordinator_exit != 0) {
      std::string status = run.launcher_status;
      for (std::size_t i = 0; i < results.outcome.cases.size(); ++i)
        if (results.outcome.cases[i].name == run.case_name && status.empty())
          status = results.outcome.cases[i].status;
      for (const auto& [name, why] : results.missing)
        if (name == run.case_name && status.empty()) status = why;
      const bool hinted = status.find("; see " + run.log_hint) != std::string::npos;
      throw ExitError(
          exit_code_of(run.coordinator_exit),
          "case " + run.case_name + ": " + status + (hinted ? "" : "; see " + run.log_hint));
    }
  }
  if (!results.missing.empty())
    throw ExitError(kExitEnvironment, "case " + results.missing.front().first + ": " +
                                          results.missing.front().second);
  for (std::size_t i = 0; i < results.facts.size(); ++i) {
    const auto& difference = results.facts[i].difference_from_in_process;
    if (difference && difference->differs())
      throw ExitError(kExitRunFailed,
                      "case " + results.outcome.cases[i].name +
                          ": the lockstep run differs from the in-process run from step " +
                          std::to_string(*difference->first_step) + " (max |du| " +
                          std::to_string(difference->max) + " m" +
                          (difference->tolerance > 0
                               ? ", beyond the frames' resolution, " + difference->resolution
                               : std::string()) +
                          ")");
  }
  fail_if_unstable(results.outcome, allow_unstable);
}

}  // namespace rths::cli
