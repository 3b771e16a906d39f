#pragma once
// Shared by the sweep's tests (grid, run, CSV, report): a small grid under the 1979 Imperial
// Valley record, first 12 s, dt = 2 ms, and how to run it.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/sweep/sweep_grid.h"
#include "analysis/sweep/sweep_run.h"
#include "study/study.h"

namespace rths::analysis::sweep_test {

inline const std::filesystem::path kMotionDir =
    std::filesystem::path(RTHS_DATA_DIR) / "ground_motions";

// A study whose sweep block holds `sweep_body`, with `integrator` added to its integrator block.
inline std::string study_text(const std::string& sweep_body, const std::string& integrator = "") {
  return R"(
name: "sweep_test"
structure { sdof { period: 0.5 } damping { modal_zeta: 0.05 } }
integrator { kind: EXPLICIT_NEWMARK )" +
         integrator + R"( }
sweep {
  motions { path: "RSN175_IMPVALL.H_H-E12140.AT2" duration: 12 }
  dts: 0.002
)" + sweep_body +
         "}\n";
}

inline SweepGrid grid_for(const std::string& sweep_body, const std::string& integrator = "") {
  return SweepGrid(study::parse_study(study_text(sweep_body, integrator), "test.textproto"),
                   kMotionDir, "test.textproto");
}

// Every point of the grid on two threads, as table rows.
inline std::vector<SweepTableRow> run_table(const SweepGrid& grid, bool general_only = false) {
  SweepOptions options;
  options.general_path_only = general_only;
  options.threads = 2;
  return to_table(grid, run_sweep(grid, options));
}

}  // namespace rths::analysis::sweep_test
