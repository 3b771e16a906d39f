#pragma once
// Every rths result as a Table (results/table.h): the one place that names the variables and
// units of each command's output, for the CSV, MATLAB and HDF5 writers and the Python module.
// A run's history has one naming (results/column_names.h) in every table that holds it: a table
// of several cases (run, launch, sites) puts "<case>_" in front of each of a case's columns; a
// record (export, read_record) is one case, named in its attribute case_name, without prefix.
//
// The tables of a study's outcome (study_table, distributed_study_table, sweep_table) are built
// where the outcome is, in analysis/tables/result_tables.h, on this naming.
// Every table of a run (those and record_table) has the attributes
//   study (text), dt_s (number, s), motion_name, motion_sha256 (SHA-256 of the motion as run:
//   dt, then the samples in m/s^2 as IEEE doubles, study::motion_key; the same in a run's
//   table and in its records' exports), motion_file_sha256 (of the file it was read from), the
//   verdict status (text) and ok (number: 1 the run(s) went as meant, 0 not).
// Numbers are number attributes (Table::set_number_attribute), the rest text.
//
//   record_table  a run record (`rths launch`, `rths export`): step, time_s,
//                 ground_acceleration_m_per_s2, u_floor<i>_m, v_floor<i>_m_per_s,
//                 a_floor<i>_m_per_s2 per DOF, command_act<j>_m, measured_act<j>_m,
//                 force_act<j>_N per actuator, then per link to node n:
//                 node<n>_answered_step, node<n>_injected_lag_s, node<n>_round_trip_s,
//                 node<n>_one_way_down_s, node<n>_one_way_up_s, with a force predictor on the
//                 link node<n>_prediction_error<j>_N (N, the error of its j-th actuator's
//                 model, core/force_predictor.h) and, for a CONTROLLER node of
//                 the header's deployment, node<n>_controller_round_trip_s (s, the UDP frame's
//                 round trip the node timed) and node<n>_controller_status (0 running) (NaN at
//                 step 0, which has no exchange), then lateness_s and overrun (0/1);
//                 attributes run_id, case_name, clock, status (the footer's, or "no footer:
//                 the run was cut short"), ok (the footer's ok; 0 without a footer), the motion
//                 from the record's inputs entry (motion_name and motion_sha256 empty for a
//                 record that does not carry it: older, or its inputs entry lost; then
//                 motion_file_sha256 is the checksum its config required, if any),
//                 integrity ("verified (CRC-32C per entry)", "damaged: <what
//                 was lost>" or "unverified: ..." for an old record, then what was assumed
//                 when every header copy was lost: the table is then sized and timed by the
//                 header the reader assumed from the steps) and lost_steps (step
//                 numbers missing from the rows, e.g. "1059-1061,2000"; empty when none).
//                 Throws std::invalid_argument for a record with neither header nor step.
//   identify_table `rths identify`: time_s, then per channel c (measured, force):
//                 c_input_m, c_target_<unit>, c_declared_<unit>, c_final_<unit> (the record, and
//                 the declared and final model's predictions over the whole record); unit m for
//                 `measured` (displacement), N for `force`.
//   hold_table    the hold of every CONTROLLER node in a record's footer
//                 (ControllerReport.hold_log), a row per frame: node, entry (0 sent HOLD,
//                 1 answer, 2 sent STOP; the text in `kind`), time_s (since the node's first HOLD
//                 frame), frame (its counter, or the answer's echo), status,
//                 position<j>_m and force<j>_N per actuator of the node (force: answers only;
//                 NaN otherwise), verdict (text: "held", "holding" or why the answer could
//                 not end the hold). No rows when no node held.

#include "identify/fit/identify.h"
#include "results/table.h"
#include "runtime/record/measurements.h"
#include "runtime/record/record.h"

namespace rths::results {

// "node<n>_<quantity>": a link's column, the same in a record and in a study's table.
std::string link_column(int node, const std::string& quantity);
// Which motion ran, as every table of a run names it: motion_name, motion_sha256 and
// motion_file_sha256 (text attributes, above).
void set_motion_attributes(Table& t, const std::string& name, const std::string& sha256,
                           const std::string& file_sha256);
// Throws std::invalid_argument when the record has no header entry.
Table record_table(const runtime::RecordContents& record);
Table identify_table(const identify::Identification& identification);
Table hold_table(const runtime::RunFooter& footer);

}  // namespace rths::results
