#pragma once
// The per-step CSV of one or more runs: the columns every command that writes a run's history
// uses (run, sdof; launch and sites should write the same through this unit).
//
// Columns, SI with the unit in every name (floors and actuators 1-based):
//   step, time_s,
//   then per run:  <run>.u_floor<i>_m          every floor's displacement relative to the ground
//                  <run>.command_act<j>_m      every actuator's commanded displacement
//                  <run>.measured_act<j>_m     its realised (measured) displacement
//                  <run>.force_act<j>_N        its measured force
// <run> is the case name with every character other than [A-Za-z0-9_] replaced by '_'.
// Row k is t_k = k dt, k = 0..N-1. A run that stopped early (diverged, a limit) leaves its cells
// empty after its last step. Numbers with 10 significant digits.

#include <filesystem>
#include <string>
#include <vector>

#include "core/simulation.h"

namespace rths::analysis {

struct NamedResult {
  std::string name;
  const core::SimulationResult* result = nullptr;
};

// The header cells of one run, in the order above.
std::vector<std::string> result_column_names(const std::string& run_name, const core::SimulationResult& result);

// Writes step, time_s and every run's columns. Throws std::invalid_argument when the runs
// differ in dt or the list is empty; std::runtime_error naming the file when it cannot be written.
void write_results_csv(const std::filesystem::path& csv, const std::vector<NamedResult>& runs);

}  // namespace rths::analysis
