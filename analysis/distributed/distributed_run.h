#pragma once
// The results of distributed runs, one way for `rths launch`, `rths sites` and any front end:
//
//   warn_past_critical_delay  before the runs start: each case's critical-delay check with the lag
//                       the deployment adds on the actuator's path (actuator_path_lag), a warning
//                       naming the parts and the margin for each case past it.
//   judge_distributed   reads each case's run record (runtime::measure_run: per-step columns, and
//                       per-link lag with its one rule for repeated answers) and judges every case
//                       against the lag-free in-process reference (analysis::judge_recorded_cases:
//                       analysis::compare on the top floor, nrmse_pct). A case whose process ran
//                       without leaving a record is listed in `missing` with why.
//   write_distributed_outputs  (distributed_outputs.h) into `out`: results.<csv|mat|h5>
//   (analysis::distributed_study_table:
//                       `rths run`'s columns for the same cases, plus lag per link), the plots of
//                       `rths run` (analysis::write_study_plots, the lag-free reference drawn
//                       beside the cases), lag_<case>.png/.svg (see write_lag_plot), summary.json
//                       and summary.txt. With plots off, stale plots go.
//   distributed_summary_text / _json   analysis::study_summary_text/_json plus per case: steps,
//                       coordinator exit, overruns, rejected messages, lag per link (median, p99,
//                       max round trip; median injected; s), each node's rejects by cause, and,
//                       for a lockstep run without node delay stages, the largest difference from
//                       the in-process run of the same case and the first step that differs (none
//                       = bit for bit). A case whose record stops before step 1 is listed in
//                       `missing` with the footer's reason.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/study_run/study_run.h"
#include "rths/proto/runtime.pb.h"
#include "runtime/record/measurements.h"
#include "study/study.h"

namespace rths::analysis {

// One case as the launcher left it.
struct DistributedRun {
  std::string case_name;
  int coordinator_exit = -1;
  std::string launcher_status;  // runtime::LaunchResult::status (empty: ran to its end)
  std::filesystem::path record;
  std::string log_hint;  // where to look when it failed
};

// The lag a distributed run adds on the actuator's path beyond the case's own delay stages, from
// the deployment; the actuator emulator node that adds the most when there are several.
struct ActuatorPathLag {
  int node_id = -1;        // the actuator emulator node (-1: the deployment has none)
  bool real_time = false;  // deployment.clock
  // s, the injected one-way lags of the node's link both ways (receive_lag + send_lag
  // one_way_delay; jitter has zero mean). In real time the coordinator uses the newest force it
  // has, so this round trip acts on the test as actuator lag; in lockstep every command waits for
  // its own answer, and it does not.
  double link_round_trip = 0.0;
  double node_stages = 0.0;  // s, nominal delay of the node's own receive_delay + send_delay stages
  // s, what the test feels: node_stages + link_round_trip in real time, node_stages in lockstep.
  double felt() const { return node_stages + (real_time ? link_round_trip : 0.0); }
};
ActuatorPathLag actuator_path_lag(const study::PreparedStudy& prepared);

// Before a distributed run starts: each named case (empty name: the reference case) checked by
// analysis::check_case_critical_delay with actuator_path_lag(prepared).felt() added to its own lag;
// for each case past its continuous or discrete critical delay, `warn` names the network
// and actuator parts of the lag, the critical delays and the margin. Returns how many are past.
int warn_past_critical_delay(const study::PreparedStudy& prepared,
                             const std::vector<std::string>& case_names,
                             const std::function<void(const std::string&)>& warn);

// The role of a link for plots and summaries: "actuator lab" (an actuator emulator's link) or
// "numerical site" (a substructure node's), followed by the site's name when the sites config
// gives one (`actuator lab "lab_b"`), else by the node id when several nodes share the role.
std::map<int, std::string> link_roles(const config::Deployment& deployment,
                                      const std::map<int, std::string>& site_of_node = {});

// A lockstep run against the in-process run of the same case.
struct InProcessDifference {
  double max = 0.0;                        // m, max |u_distributed - u_in_process|
  std::optional<std::int64_t> first_step;  // the first step that differs; none = bit for bit
  // m: what the controller frames' rounding may move the run by (0: none rounds, bit for bit
  // is the test), and how it was derived ("" when 0).
  double tolerance = 0.0;
  std::string resolution;
  bool differs() const { return first_step && max > tolerance; }
};

// The tolerance of a lockstep run through controller frames against the in-process run, from
// the frames' layouts: 0 when every field that carries a displacement or force crosses
// unchanged (F64 at scale 1). A float field (F32, or F64 with a scale) rounds each value by
// 2^-24 (F32) or 2^-52 of it, at most 3 roundings per step (target out, displacement and
// force back), amplified by at most 1 / (2 zeta) ~ 10 on a lightly damped structure: allowed
// 1e-5 x peak |u| (F32; 5x margin) or 1e-12 x peak |u|. An integer field rounds by half its
// scale: allowed 1e-3 x peak |u|. Returns {tolerance in m, how it was derived}.
std::pair<double, std::string> frame_rounding_tolerance(const config::Deployment& deployment,
                                                        double peak_displacement);

// From a run record's steps: the step's own work (StepRecord.step_wall of the steps after step 0:
// its exchange with the nodes and its integration, s), median and p99, and the time from the
// header (written as the coordinator starts up) to step 1's start (s: the nodes' start-up and the
// loop's set-up); 0 where the record has none.
struct StepTiming {
  double work_median = 0.0, work_p99 = 0.0;  // s
  double start_to_step1 = 0.0;               // s
};
StepTiming step_timing(const runtime::RecordContents& record);

struct DistributedCaseFacts {
  int coordinator_exit = -1;
  std::uint64_t overruns = 0, rejected = 0;  // rejected: the coordinator's, every cause
  std::uint64_t unauthenticated = 0;         // the coordinator's drops for want of a MAC (footer)
  std::filesystem::path record;
  std::map<int, std::string> link_labels;  // node id -> link_roles' label
  std::optional<InProcessDifference> difference_from_in_process;
  std::vector<runtime::NodeRejects> node_rejects;  // the footer's: each node's, by cause
  // A real-time run that missed its deadlines: why, what to do, what the record is good for
  // (runtime::diagnose_deadlines); empty otherwise.
  std::string deadline_diagnosis;
  StepTiming timing;  // the per-step cost and the start-up, from the record
};

struct DistributedResults {
  analysis::StudyOutcome outcome;                            // cases that left a record
  std::vector<DistributedCaseFacts> facts;                   // per outcome.cases[i]
  std::vector<std::map<int, runtime::LinkSeries>> links;     // per outcome.cases[i]
  std::vector<std::pair<std::string, std::string>> missing;  // case, why no record
  ActuatorPathLag actuator_path;  // each case's stability check includes actuator_path.felt()
};

// site_of_node: node id -> site name (`rths sites`), for the link labels.
// A record's own warning (damaged entries) goes to `warn`.
DistributedResults judge_distributed(const study::PreparedStudy& prepared,
                                     const std::vector<DistributedRun>& runs,
                                     const std::function<void(const std::string&)>& warn,
                                     const std::map<int, std::string>& site_of_node = {});

std::string distributed_summary_text(const DistributedResults& results);
nlohmann::json distributed_summary_json(const DistributedResults& results);

}  // namespace rths::analysis
