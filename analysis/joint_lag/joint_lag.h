#pragma once
// The joint study: network lag x actuator lag on one study (the paper's frame), error surface and
// measured total lag against the injected parts.
//
// Emulated grid (in process, simulated time, deterministic): for every (network round trip R,
// actuator lag A) the experimental actuator's chain is [shift(R), actuator(A)], where actuator is
// shift(A) or a first-order lag with time constant A. For an elastic specimen (force = k u, as in
// the paper's frame) delaying the force by the up-link equals delaying the displacement by it, so
// down-link + up-link enter as one shift by their sum R.
// Per point:
//   error            E_peak and E_rms (%, analysis/common/compare.h) lead; the paper's NRMSE
//                    sqrt(mean e^2) / median|u_ref| and its Eq. 2 follow
//   measured total   J1 delay of the realised behind the commanded displacement (cross-correlation
//                    peak, s), compared with injected = R + A.
// Measured across sites (optional, needs namespaces): selected points run across network-namespace
// sites by a JointLagAcrossSites runner (deploy/joint_lag_sites.h, which analysis/ does not link),
// and the record's measured lags are compared with the injected parts; see there.
//
// Stability: before the grid runs, the continuous boundary R*(A) (BoundaryPoint; SDOF studies),
// with a force predictor the compensated one for any structure (core::setup_loop_stability);
// grid points past it are flagged (past_boundary) and a warning names how many.
//
// Outputs (in the output directory): grid.csv, measured.csv (peak_error_pct, rms_error_pct first,
// then the paper's nrmse_pct), error_map.png and .svg (2-D heat map of E_rms %, log colour scale,
// contour lines,
// the stability boundary, diverged points marked), total_lag.png and .svg (measured vs injected),
// summary.json.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/joint_lag/joint_lag_result.h"
#include "rths/analysis/joint_lag.pb.h"
#include "rths/proto/config.pb.h"

namespace rths::analysis {

// Reads and checks a JointLagStudy (text format). Throws std::invalid_argument naming the file
// and the field (an empty study or grid, a lag that is negative or not finite).
JointLagStudy load_joint_lag(const std::filesystem::path& path);

// Runs the across-sites part of the study (deploy::joint_lag_across_sites() gives the one that
// runs across network-namespace sites).
struct JointLagAcrossSites {
  // Why runs across sites are impossible here (e.g. namespaces not permitted); empty when possible.
  std::function<std::optional<std::string>()> unavailable;
  // Runs every (measured_network_round_trips x measured_actuator_lags) point of `config` (paths
  // relative to `base_dir`) into result.output_directory, appends one point each to
  // result.measured, and calls one_done after each. Throws std::runtime_error when a run fails.
  std::function<void(const JointLagStudy& config, const std::filesystem::path& base_dir,
                     JointLagResult& result, const std::function<void()>& one_done)>
      run;
};

struct JointLagOptions {
  std::optional<std::filesystem::path> output_directory;  // overrides the config's
  bool measure = true;  // run the across-sites part when the config asks and it is possible
  bool plots = true;
  // The across-sites runner; without one the across-sites part is skipped (and says so).
  JointLagAcrossSites across_sites;
  // Called after each grid point and each across-sites run: done of total (both counted).
  std::function<void(std::size_t done, std::size_t total)> progress;
  // Before the grid runs: a warning for the user (points past the stability boundary); unset,
  // it goes to the log.
  std::function<void(const std::string& warning)> warn;
};

JointLagResult run_joint_lag(const JointLagStudy& config, const std::filesystem::path& base_dir,
                             const JointLagOptions& options);

// Writes the CSVs, summary.json and (if plots) the PNGs into result.output_directory.
void write_joint_lag_outputs(const JointLagResult& result, bool plots);

nlohmann::json to_json(const JointLagResult& result);
// The grid as a table (E_rms), then each across-sites run with its measured lags and its E_rms beside
// the in-process run of the lags its response sees (a lockstep run says plainly that it cannot
// check the map's network axis).
std::string to_text(const JointLagResult& result);
// Grid and across-sites points that diverged (fill_joint_lag_errors' verdict).
std::size_t diverged_points(const JointLagResult& result);

// --- shared with the across-sites runner -------------------------------------------------------
// The actuator's own stage: a shift by `lag` (s), or a first-order lag of time constant `lag`.
config::DelayStage joint_lag_actuator_stage(JointLagStudy::ActuatorModel model, double lag);
// The J1 search window (s): max_lag_search, or 2 x the largest injected total + 10 ms.
double joint_lag_search_window(const JointLagStudy& config);
// E_peak, E_rms, the paper's NRMSE and Eq. 2, the peak error of `u` against `reference` (m) over their common
// length (a diverged run is shorter) and the verdict, into `point`, as `rths run` judges a case:
// analysis::compare (stopped early, not finite, or grown past core::kDivergenceGrowth times the
// reference's peak), or past the stability boundary (point.past_boundary) with an envelope that
// grows exponentially over its last cycles of `growth_period` (s; analysis::diverging, u sampled
// at dt, s). growth_period 0: compare's rule alone.
void fill_joint_lag_errors(JointLagPoint& point, const std::vector<double>& reference,
                           const std::vector<double>& u, bool stopped_early, double dt = 0.0,
                           double growth_period = 0.0);

}  // namespace rths::analysis
