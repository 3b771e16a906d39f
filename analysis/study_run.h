#pragma once
// One study, every case: runs each case of a prepared study in process, compares it with the
// reference case, and writes the CSV, plots and summary a user reads.
//
// Compared quantity: the top-floor displacement (m) relative to the ground (DOF 0 of an SDOF).
// Metrics per case against the reference: the paper's Eq. 2 as printed, NRMSE, peak error, and
// the peaks. A case whose response grew past the divergence bound is flagged `diverged`.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/simulation.h"
#include "core/study.h"

namespace rths::analysis {

struct CaseOutcome {
  std::string name;
  std::string delay_description;  // e.g. "shift(14 ms)"
  double nominal_delay = 0.0;     // s, low-frequency lag of the chain (negative = lead)
  core::SimulationResult simulation;
  std::vector<double> response;   // m, top-floor displacement
  double peak = 0.0;              // m, max |response|
  double paper_eq2 = 0.0, nrmse = 0.0, peak_error = 0.0;  // vs the reference case
};

struct StudyOutcome {
  std::string study_name;
  std::size_t reference_index = 0;
  std::vector<CaseOutcome> cases;
};

StudyOutcome run_study(const core::PreparedStudy& prepared);

// displacement.png (reference vs each case, the paper's Fig. 3) and
// force_displacement.png (command vs measured force: the loop the integrator sees, Figs. 1-2).
void write_study_plots(const StudyOutcome& outcome, const std::filesystem::path& directory);
nlohmann::json study_summary_json(const StudyOutcome& outcome);
std::string study_summary_text(const StudyOutcome& outcome);

}  // namespace rths::analysis
