#pragma once
// Running a sweep grid (analysis/sweep/sweep_grid.h), and its stability before it runs.
//
// Per grid point (SI units): the reference is the purely numerical structure (alpha = 0) without
// delay; the delayed run splits the storey into (1 - alpha) k numerical and alpha k experimental
// behind the delay. Outputs: peak |u| of both (m); the errors every rths output leads with,
// E_peak and E_rms (%, analysis/common/compare.h); the peak error (m); the paper's NRMSE (%) and Eq. 2
// as printed, kept for its Fig. 4; and whether the delayed run diverged (then the error measures
// are inf): stopped, grew past 10x the reference, or past its critical delay with an
// exponentially growing envelope (analysis::diverging, as `rths run` judges a case).
//
// Linear SDOF cases with explicit Newmark and a shift (or no) delay run on the SIMD batch kernel
// (analysis/sweep/batch_kernel.h); everything else through core::simulate. Both agree to round-off,
// and a point's numbers do not depend on the shard or thread that computed it.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/sweep/sweep_grid.h"

namespace rths::analysis {

struct SweepRow {
  SweepPoint point;
  double peak_reference = 0, peak_delayed = 0;  // m
  // inf when diverged: E_peak, E_rms (%), max|e| (m); the paper's NRMSE (%) and Eq. 2 (-).
  double peak_error_pct = 0, rms_error_pct = 0, peak_error = 0;
  double nrmse_pct = 0, eq2_paper = 0;
  // analysis::compare: stopped, not finite, or grew past 10x the reference; or diverging as
  // `rths run` judges it: past its critical delay, its envelope growing exponentially.
  bool diverged = false;
};

struct SweepOptions {
  Shard shard;
  int threads = 0;  // 0: every core
  // Run every point through core::simulate, even where the batch kernel applies (tests compare).
  bool general_path_only = false;
  // Called from worker threads, serialised, after each finished work item.
  std::function<void(std::size_t done_points, std::size_t total_points)> progress;
};

// Before a sweep: every (period, fraction, dt, delay) of the grid against its critical delay
// (core::check_critical_delay on the SDOF with the study's damping and integrator).
struct SweepStabilityCheck {
  std::size_t combinations = 0, past = 0;  // (period, fraction, dt, delay > 0) checked, and past
  double smallest_margin = 1.0;            // core::CriticalDelayCheck::margin of the worst one
  std::string worst;                       // "T = 0.05 s, alpha = 0.333, dt = 1 ms: lag 14 ms ..."
};
SweepStabilityCheck check_sweep_stability(const SweepGrid& grid);

// Critical delay (s) of a period (s), fraction and dt (s); empty when stable for every delay.
using CriticalDelayOf =
    std::function<std::optional<double>(double period, double alpha, double dt)>;
// The critical delay of the grid's SDOF (study damping and integrator): core::check_critical_delay.
CriticalDelayOf critical_delay_of(const SweepGrid& grid);

// Rows of the shard, in index order. Throws std::invalid_argument when the shard is not 0 <= i < N.
std::vector<SweepRow> run_sweep(const SweepGrid& grid, const SweepOptions& options);

// A row with the names of its motion and model as text: what a sweep CSV holds
// (analysis/sweep/sweep_csv.h) and what the report reads (analysis/sweep/sweep_report.h).
struct SweepTableRow {
  std::size_t index = 0;
  double period = 0, delay = 0, alpha = 0, stiffness = 0, dt = 0;
  std::string motion, model;
  double peak_reference = 0, peak_delayed = 0;
  double peak_error_pct = 0, rms_error_pct = 0, peak_error = 0, nrmse_pct = 0, eq2_paper = 0;
  bool diverged = false;
};
std::vector<SweepTableRow> to_table(const SweepGrid& grid, const std::vector<SweepRow>& rows);

}  // namespace rths::analysis
