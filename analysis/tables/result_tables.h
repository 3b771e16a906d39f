#pragma once
// The tables of a study's outcome (results/table.h), named by results/column_names.h and written
// by results/write.h as CSV, MATLAB or HDF5. Their run attributes (study, dt_s, the motion,
// status, ok) are those of every table of a run (results/results.h).
//
//   study_table   `rths run`: step, time_s, then per case what the study's recorders keep
//                 (study/recorders.h; by default every floor and every actuator up to 200 DOFs):
//                 <case>_u_floor<i>_m, v_floor<i>_m_per_s, a_floor<i>_m_per_s2,
//                 drift_floor<i>_floor<j>_m, base_shear_N, and per actuator
//                 <case>_command_act<j>_m, <case>_measured_act<j>_m, <case>_force_act<j>_N. A row
//                 per step some recorder keeps (`step` says which), a recorder's column NaN at
//                 the steps it does not keep. A case that stopped early (diverged) is NaN after
//                 its last step. status: "completed" when every case completed, else
//                 "<case>: <status>" of each case that did not, joined by "; "; ok 1 when every
//                 case completed or diverged as its expect_unstable said. Also reference_case
//                 and reference.
//   distributed_study_table  `rths launch` and `rths sites`: study_table's columns (the same as
//                 `run`'s for the same cases), then the lag per link of each case:
//                 <case>_node<n>_injected_lag_s and <case>_node<n>_round_trip_s (s), filled at
//                 the step that carried each answer (runtime/record/measurements.h: an answer
//                 counts once) and NaN elsewhere (step 0; a real-time step that reused an older
//                 answer). Attribute "reference": against what every case was compared.
//   sweep_table   `rths sweep`: index, period (s), delay (s), alpha, stiffness (N/m; 0 = mass
//                 1 kg), dt (s), motion and model (text), peak_ref, peak_delayed (m),
//                 peak_error_pct (E_peak), rms_error_pct (E_rms), peak_error (m), the
//                 paper's nrmse_pct and eq2_paper, diverged (0/1), as in the sweep CSV;
//                 attributes grid_hash and grid_points.

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "analysis/study_run/study_run.h"
#include "analysis/sweep/sweep_run.h"
#include "results/table.h"
#include "runtime/record/measurements.h"

namespace rths::analysis {

results::Table study_table(const StudyOutcome& outcome);
// study_table's rows and columns for `cases` cases of `steps` steps with `actuators` actuators
// under `plan`, before any of it runs (a CSV past a spreadsheet is refused before the run).
struct TableShape {
  std::size_t rows = 0, columns = 0;
};
TableShape study_table_shape(const study::RecorderPlan& plan, std::size_t steps, std::size_t cases,
                             std::size_t actuators);
// links[i]: the per-link series of outcome.cases[i] (runtime::measure_run); sizes must agree.
results::Table distributed_study_table(
    const StudyOutcome& outcome, const std::vector<std::map<int, runtime::LinkSeries>>& links);
results::Table sweep_table(const std::vector<SweepTableRow>& rows, const std::string& grid_hash,
                           std::size_t grid_points);

}  // namespace rths::analysis
