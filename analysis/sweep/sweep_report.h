#pragma once
// What a sweep shows: its figures, and the paper's claims measured on its rows
// (analysis/sweep/sweep_run.h's SweepTableRow, from a run or read back from a CSV).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/sweep/sweep_run.h"

namespace rths::analysis {

// Two figures (PNG and SVG), at the first stiffness (the others coincide):
//   `png`: E_rms (%) against period on a log axis, one curve per delay (and per model, fraction,
//     dt and record when there are several; colour by delay, dash by model), each curve's
//     diverged points marked in its colour on a row of its own above the curves (they set no
//     scale, and every one is seen); below it, the same for the paper's Fig. 4 (its NRMSE) and
//     the paper's Eq. 2 as printed.
//   sweep_delay_plot_path(png): E_rms against delay (ms), one curve per period (at most 6, spread
//     over the range) and model, with each period's critical delay drawn when `critical_delay`
//     is given.
// Needs gnuplot. Throws std::invalid_argument when there are no rows or no delay > 0.
void write_sweep_plot(const std::vector<SweepTableRow>& rows, const std::filesystem::path& png,
                      const std::string& title, const CriticalDelayOf& critical_delay = {});
// A sweep model's name as a legend reads it: "bilinear:uy=0.005:b=0.1" -> "bilinear (uy = 5 mm,
// b = 0.1)"; "linear" stays.
std::string model_label(const std::string& model);
// "out/sweep.png" -> "out/sweep_vs_delay.png".
std::filesystem::path sweep_delay_plot_path(const std::filesystem::path& png);

// The paper's claims, measured on the rows with one error measure e: E_rms, which rths leads
// with, or the paper's own NRMSE (kept in the JSON, labelled, to compare with the paper).
enum class SweepMeasure { kErms, kPaperNrmse };
struct SweepTrends {
  // max over (period, delay, ...) of |e(k1) - e(k2)| / max|e| across stiffnesses; 0 when only one
  // stiffness was swept.
  double stiffness_max_relative_difference = 0;
  // Per delay > 0 series: fraction of consecutive period pairs where e falls (1 = monotone).
  double period_falling_fraction = 0;
  // Median over periods of e(non-linear model) / e(linear), when both were swept; NaN otherwise.
  // < 1: the softening model has the smaller delay error.
  double nonlinear_to_linear_median_ratio = 0;
  std::size_t diverged_points = 0;
};
SweepTrends measure_trends(const std::vector<SweepTableRow>& rows,
                           SweepMeasure measure = SweepMeasure::kErms);
// What `rths sweep --json` and rths.sweep() carry: {"trends": with E_rms, "paper_trends": with
// the paper's NRMSE}, each {measure, stiffness_max_relative_difference,
// period_falling_pair_fraction, nonlinear_to_linear_median_ratio (null when not measured),
// diverged_points}.
nlohmann::json sweep_trends_json(const std::vector<SweepTableRow>& rows);

}  // namespace rths::analysis
