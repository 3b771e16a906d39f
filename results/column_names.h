#pragma once
// The per-step columns of one or more runs: the names every command that writes a run's history
// uses (run, sdof, launch, sites: analysis::study_table; export and read_record: results::
// record_table, the same names without the case prefix; written as CSV, MATLAB or HDF5 by
// results::write_table).
//
// Columns, SI with the unit in every name (floors and actuators 1-based):
//   step, time_s,
//   then per run:  <run>_u_floor<i>_m          every floor's displacement relative to the ground
//                  <run>_command_act<j>_m      every actuator's commanded displacement
//                  <run>_measured_act<j>_m     its realised (measured) displacement
//                  <run>_force_act<j>_N        its measured force
// <run> is the case name with every character other than [A-Za-z0-9_] replaced by '_'.
// A record (one run) also has v_floor<i>_m_per_s and a_floor<i>_m_per_s2 (velocity and
// acceleration relative to the ground). "Floor" is the structure's i-th DOF. A study's recorders
// (study/recorders.h) choose which of these a run's table has, and add
// <run>_drift_floor<i>_floor<j>_m (u_i - u_j; floor0 is written "ground") and
// <run>_base_shear_N.
// Row k is t_k = k dt, k = 0..N-1. A run that stopped early (diverged, a limit) leaves its cells
// empty (NaN) after its last step.

#include <filesystem>
#include <string>
#include <vector>

#include "core/simulation.h"

namespace rths::results {

struct NamedResult {
  std::string name;
  const core::SimulationResult* result = nullptr;
};

// "<run>_": the prefix of every column of one run (the case name made safe as above).
std::string result_column_prefix(const std::string& run_name);

// One floor's (i) or one actuator's (j) column without the prefix, 1-based: "u_floor1_m",
// "v_floor1_m_per_s", "a_floor1_m_per_s2", "command_act1_m", "measured_act1_m", "force_act1_N".
std::string displacement_column(std::size_t floor);
std::string velocity_column(std::size_t floor);
std::string acceleration_column(std::size_t floor);
std::string command_column(std::size_t actuator);
std::string measured_column(std::size_t actuator);
std::string force_column(std::size_t actuator);
// A drift recorder's column, 1-based DOFs, 0 the ground: "drift_floor5_floor4_m",
// "drift_floor1_ground_m" (u[upper] - u[lower], m).
std::string drift_column(std::size_t upper, std::size_t lower);
inline constexpr const char* kBaseShearColumn = "base_shear_N";

// The header cells of one run, in the order above.
std::vector<std::string> result_column_names(const std::string& run_name,
                                             const core::SimulationResult& result);

}  // namespace rths::results
