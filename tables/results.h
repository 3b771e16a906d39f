#pragma once
// Every rths result as a Table (tables/table.h): the one place that names the variables and
// units of each command's output, for the CSV, MATLAB and HDF5 writers and the Python module.
//
//   study_table   `rths run`: time_s, u_<case>_m per case (top-floor displacement relative to
//                 the ground), then command_<case>_m, realised_<case>_m, force_<case>_N of the
//                 first actuator for each case that has one. A case that stopped early (diverged)
//                 is NaN after its last step.
//   sweep_table   `rths sweep`: index, period (s), delay (s), alpha, stiffness (N/m; 0 = mass
//                 1 kg), dt (s), motion and model (text), peak_ref, peak_delayed (m),
//                 eq2_paper, nrmse, peak_error (m), diverged (0/1), as in the sweep CSV;
//                 attributes grid_hash and grid_points.
//   record_table  a run record (`rths launch`, `rths export`): step, time (s),
//                 ground_acceleration (m/s^2), u<i> (m), v<i> (m/s), a<i> (m/s^2) per DOF,
//                 command<j>, realised<j> (m), force<j> (N) per actuator, then per link to node n:
//                 node<n>_answered_step, node<n>_injected_lag, node<n>_round_trip,
//                 node<n>_one_way_down, node<n>_one_way_up (s; NaN at step 0, which has no
//                 exchange), then lateness (s) and overrun (0/1); attributes run_id, case_name,
//                 clock, status.
//   identify_table `rths identify`: time_s, then per channel c (measured, force):
//                 c_input_m, c_target_<unit>, c_declared_<unit>, c_final_<unit> (the record, and
//                 the declared and final model's predictions over the whole record); unit m for
//                 `measured` (displacement), N for `force`.

#include "analysis/study_run.h"
#include "analysis/sweep.h"
#include "identify/identify.h"
#include "runtime/record.h"
#include "tables/table.h"

namespace rths::tables {

Table study_table(const analysis::StudyOutcome& outcome);
Table sweep_table(const std::vector<analysis::SweepTableRow>& rows, const std::string& grid_hash,
                  std::size_t grid_points);
// Throws std::invalid_argument when the record has no header entry.
Table record_table(const runtime::RecordContents& record);
Table identify_table(const identify::Identification& identification);

}  // namespace rths::tables
