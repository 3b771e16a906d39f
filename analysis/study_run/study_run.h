#pragma once
// One study, every case: checks each case against its critical delay before it runs, runs it in
// process, judges it, compares it with the reference case, and writes the CSV, plots and summary.
//
// Before each case: core::check_critical_delay on the structure, the case's lag (the delay
// chain's nominal delay, the largest over actuators) and the integrator; a case past the limit
// is announced through RunStudyOptions::warn with the margin. Cases whose loops are the same
// (the same specimens on the same structure) share one check, made at the largest of their lags
// (its discrete search reaches every smaller lag's), each case then judged at its own lag. A
// case with compensation is judged on its compensated loop instead (CompensatedVerdict): a
// linear one analysed, an adaptive one stated as not analysable, with the uncompensated margin
// beside. A run lasting more than a few seconds reports its progress (RunStudyOptions::progress).
// After each case, its status:
//   "limit tripped"  |u| or |v| of a floor passed deployment.limits (applied in process as the
//                    coordinator applies them distributed: the run stops before that step)
//   "diverged"       judged from the response: the top-floor peak grew past
//                    core::kDivergenceGrowth times the lag-free run's (same structure, no delay
//                    stage), or the simulation's own guard stopped it
//   "diverging"      past its critical delay (judged_past) and the top floor's envelope grows
//                    exponentially over the record's last cycles (core::envelope_growth, windows
//                    of the check's governing period), whatever its peak ratio
//   "completed"      otherwise; a case inside its critical delay whose envelope grows stays
//                    completed, with the fitted rate in status_detail (flagged, not failed)
// Compared quantity: the top-floor displacement (m) relative to the ground (analysis::compare).
// A run failed its purpose when a case diverged or is diverging without `expect_unstable`, or a
// limit tripped.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/common/compare.h"
#include "analysis/study_run/actuator_names.h"
#include "analysis/study_run/compensated_verdict.h"
#include "analysis/study_run/run_progress.h"
#include "core/envelope_growth.h"
#include "core/simulation.h"
#include "core/stability.h"
#include "study/study.h"

namespace rths::analysis {

struct CaseOutcome {
  std::string name;
  std::string delay_description;  // e.g. "shift(14 ms)"
  double nominal_delay = 0.0;     // s, low-frequency lag of the chain (negative = lead)
  bool expect_unstable = false;
  std::optional<core::CriticalDelayCheck> stability;  // empty: no experimental part
  // A case with compensation: the compensated loop's own verdict (judge_compensated_loop);
  // `stability` above stays the uncompensated lag's check, shown beside it.
  std::optional<CompensatedVerdict> compensated;
  // The actuators (0-based) whose force a predictor compensates (core/force_predictor.h); their
  // errors are in simulation.prediction_error and the summary (prediction_error_text/_json).
  std::vector<int> predicted_actuators;
  // Per actuator, when the case has a link (Case.link): what its answers did over the record
  // (core/link_answers.h); empty without one.
  std::vector<core::LinkAnswerStats> link_answers;
  // The top floor's envelope over the last cycles (core::envelope_growth at the check's governing
  // period); empty without a check or when the record is too short to fit.
  std::optional<core::EnvelopeGrowth> growth;
  core::SimulationResult simulation;
  std::vector<double> response;  // m, top-floor displacement
  Comparison comparison;         // against the reference case
  // "completed", "diverged", "diverging", "limit tripped", "held" (a force predictor past its
  // bound stopped it; status_detail names the link)
  std::string status = "completed";
  std::string status_detail;  // why, when not completed; a growth flag when completed
  // Diverged or diverging: the run failed its purpose unless expected, and its errors measure
  // nothing.
  bool diverged() const { return status == "diverged" || status == "diverging"; }
  // Before the run, the case was judged unstable: uncompensated, its lag is past the critical
  // delay; compensated, its analysed loop is unstable, or (not analysable) its uncompensated lag
  // is past.
  bool judged_past() const;
};

inline constexpr const char* kLagFreeReference = "the lag-free in-process reference";

struct StudyOutcome {
  std::string study_name;
  std::string motion_units;  // units the record was read in: g, m/s2, cm/s2, in/s2, mm/s2
  // The record as read: points, dt, duration, PGA in its units, where they came from.
  std::string motion_description;
  // Which motion ran: its name (file stem or header title), the SHA-256 of the motion as run
  // (motion_key: dt, then the samples in m/s^2 as IEEE doubles; the same for a run and its
  // record) and of the file it was read from ("" when it came from no file).
  std::string motion_name, motion_sha256, motion_file_sha256;
  ResponseSpec response = ResponseSpec::floor(1);
  // What the results table holds of each case (study/recorders.h); no channels: every DOF's
  // displacement the case kept and every actuator.
  study::RecorderPlan recorders;
  // What the figures and the summary call each actuator, and their order (actuator_names.h).
  ActuatorNames actuators;
  std::size_t reference_index = 0;
  double lag_free_peak = 0.0;  // m, top floor of the run without any delay stage
  std::vector<CaseOutcome> cases;
  // Distributed runs (judge_recorded_cases): the lag-free in-process run every case is compared
  // with. Empty for `run`, which compares every case with cases[reference_index].
  std::optional<CaseOutcome> lag_free_reference;
  const CaseOutcome& reference() const;
  // kLagFreeReference, or "case '<name>'".
  std::string reference_description() const;
  // Cases that make the run fail its purpose: diverged without expect_unstable (unless
  // `allow_unstable`), or a limit tripped.
  std::vector<std::string> failures(bool allow_unstable) const;
};

struct RunStudyOptions {
  std::function<void(const std::string&)> warn;  // pre-run warnings (stderr in the CLI)
  // s, lag on the actuator's path that the case's own delay stages do not hold (a distributed
  // run's network round trip and node delay stages), added to each case's lag in its check.
  double extra_lag = 0.0;
  // Progress lines of a long run (analysis/study_run/run_progress.h); none without a print.
  ProgressOptions progress = {};
};

// The critical-delay check of one case before it runs, the one run_study and judge_recorded_cases
// make: core::check_critical_delay on the structure, the integrator and the lag tau = the case's
// delay chain's nominal delay (s, the largest over actuators; negative = lead) + extra_lag (s).
// Empty when the structure has no experimental part.
// A case with a force predictor: its loop's verdict (core::predictor_critical_delay for the model
// as it starts) at the case's lag plus `extra_lag` (s, a link's round trip); empty without one.
std::optional<CompensatedVerdict> predicted_loop_verdict(const study::PreparedStudy& prepared,
                                                         const config::Case& study_case,
                                                         double extra_lag);
std::optional<core::CriticalDelayCheck> check_case_critical_delay(
    const study::PreparedStudy& prepared, const config::Case& study_case, double extra_lag = 0.0);

// What run_study knows of a case before it runs it (nothing is announced): name, delay, its
// critical-delay check (`stability`) and, with compensation, its compensated loop's verdict
// (`compensated`: exact on one DOF, the modal approximation on several). Throws
// std::invalid_argument for a case the study lacks.
CaseOutcome pre_run_verdict(const study::PreparedStudy& prepared, const std::string& case_name);

StudyOutcome run_study(const study::PreparedStudy& prepared, const RunStudyOptions& options = {});

// A case that ran elsewhere (`rths launch`, `rths sites`), as its record tells it.
struct RecordedCase {
  std::string name;                   // a case of the study
  core::SimulationResult simulation;  // per-step history (runtime::measure_run); diverged = the
                                      // coordinator's own guard stopped it
  std::string status = "completed";   // "completed", or why the run stopped
  std::string status_detail;          // e.g. the launcher's reason, the coordinator log's tail
};

// Distributed cases judged as run_study judges in-process ones (critical-delay check, divergence
// from the response against the lag-free run), and each compared (analysis::compare, top floor)
// with the lag-free in-process run of the same structure and motion (prepared.base: no delay
// stage, no network), which the outcome keeps as lag_free_reference. A recorded case's status
// other than "completed" is kept. Throws std::invalid_argument for a case the study lacks.
StudyOutcome judge_recorded_cases(const study::PreparedStudy& prepared,
                                  std::vector<RecordedCase> cases,
                                  const RunStudyOptions& options = {});

// The results file (csv, mat, h5) is analysis::study_table: results/column_names.h columns.
// displacement.png/.svg, three panels (mm): every case with the reference (the paper's Fig. 3),
// each case minus the reference, and a zoom on the reference's strongest 5 s; the axes follow the
// cases that stayed bounded (a diverged case is clipped and labelled). force_displacement.png/.svg:
// command vs measured force of the bounded cases (the loop the integrator sees, Figs. 1-2).
// tracking.png/.svg (the RTHS benchmark's tracking figure): per bounded case with an actuator,
// x_t (command) and x_m (measured) at actuator 1 (mm) over the record and over a 1 s zoom on the
// reference's strongest second; absent when no case has an actuator. A case stopped early (a
// limit, its predictor's bound) is drawn up to its stop, a dashed line there naming why, and its
// tracking zoom is its last second when it stopped before the reference's strongest one ended.
// Then a model's envelope over height, its chosen floors and every actuator, a page of them at a
// time (analysis/study_run/response_envelope_plots.h), where the study has several floors or actuators.
// Returns the PNG files written (names in `directory`, each with its SVG beside it); a figure the
// study has nothing for is removed.
// Throws std::runtime_error when gnuplot fails (no figure is then written).
std::vector<std::string> write_study_plots(const StudyOutcome& outcome,
                                           const std::filesystem::path& directory);
// The files write_study_plots writes, so a run without plots can remove stale ones.
std::vector<std::string> study_plot_files();
// The errors each summary leads with (analysis::compare), defined where they are printed.
inline constexpr const char* kPeakErrorDefinition =
    "100 max|u - u_ref| / max|u_ref| (%, the peak error against the reference's peak)";
inline constexpr const char* kRmsErrorDefinition =
    "100 sqrt(sum (u - u_ref)^2 / sum u_ref^2) (%, the RMS error against the reference's RMS)";
// {field: definition} of every error field a case's summary carries.
nlohmann::json error_measures_json();
// Per case: status, stability check, envelope_growth (null without a fit), peak_displacement_m,
// then the errors against the reference: peak_error_pct (E_peak) and rms_error_pct (E_rms) lead,
// peak_error_m, and the paper's nrmse_pct and paper_eq2_as_printed; all null when the case stopped
// before the reference's end (steps_compared < reference_steps), whose errors over the steps it
// covered are in errors_over_covered_steps. "measures" defines every error field.
nlohmann::json study_summary_json(const StudyOutcome& outcome);
// The table leads with E_peak and E_rms ("-" for a case that diverged or stopped early, whose
// covered steps' errors follow on a line of their own), their definitions below it.
std::string study_summary_text(const StudyOutcome& outcome);

}  // namespace rths::analysis
