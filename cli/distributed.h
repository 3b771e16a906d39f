#pragma once
// The results of distributed runs, one way for `rths launch` and `rths sites`:
//
//   judge_distributed   reads each case's run record (runtime::measure_run: per-step columns, and
//                       per-link lag with its one rule for repeated answers) and judges every case
//                       against the lag-free in-process reference (analysis::judge_recorded_cases:
//                       analysis::compare on the top floor, nrmse_pct). A case whose process ran
//                       without leaving a record is listed in `missing` with why.
//   write_distributed_outputs  into `out`: results.<csv|mat|h5> (tables::distributed_study_table:
//                       `rths run`'s columns for the same cases, plus lag per link), the plots of
//                       `rths run` (analysis::write_study_plots, the lag-free reference drawn
//                       beside the cases), lag_<case>.png (injected and measured round trip per
//                       link, ms), summary.json and summary.txt. With plots off, stale plots go.
//   distributed_summary_text / _json   analysis::study_summary_text/_json plus per case: steps,
//                       coordinator exit, overruns, rejected messages, lag per link (median, p99,
//                       max round trip; median injected; s), and, for a lockstep run without node
//                       delay stages, the largest difference from the in-process run of the same
//                       case (0 = bit for bit).

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/study_run.h"
#include "core/study.h"
#include "runtime/measurements.h"

namespace rths::cli {

// One case as the launcher left it.
struct DistributedRun {
  std::string case_name;
  int coordinator_exit = -1;
  std::string launcher_status;          // runtime::LaunchResult::status (empty: ran to its end)
  std::filesystem::path record;
  std::string log_hint;                 // where to look when it failed
};

struct DistributedCaseFacts {
  int coordinator_exit = -1;
  std::uint64_t overruns = 0, rejected = 0;
  std::filesystem::path record;
  std::map<int, std::string> link_labels;  // node id -> "node 2 (actuator_emulator)"
  std::optional<double> max_difference_from_in_process;  // m
};

struct DistributedResults {
  analysis::StudyOutcome outcome;                        // cases that left a record
  std::vector<DistributedCaseFacts> facts;               // per outcome.cases[i]
  std::vector<std::map<int, runtime::LinkSeries>> links; // per outcome.cases[i]
  std::vector<std::pair<std::string, std::string>> missing;  // case, why no record
};

DistributedResults judge_distributed(const core::PreparedStudy& prepared,
                                     const std::vector<DistributedRun>& runs);

// Returns the results file written.
std::filesystem::path write_distributed_outputs(const DistributedResults& results,
                                                const std::filesystem::path& out, bool plots,
                                                const std::string& format);
std::string distributed_summary_text(const DistributedResults& results);
nlohmann::json distributed_summary_json(const DistributedResults& results);

// Exit status of distributed cases: the first failing coordinator's (1 run failed, 2 bad config,
// else 3 environment), then a case that left no record (3), then a diverged case (1; unless
// allow_unstable or expect_unstable). Throws ExitError; returns when every case passed.
void fail_if_distributed_failed(const DistributedResults& results,
                                const std::vector<DistributedRun>& runs, bool allow_unstable);

}  // namespace rths::cli
