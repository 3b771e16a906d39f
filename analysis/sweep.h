#pragma once
// The paper's Fig. 4 study as a grid: periods x delays x experimental fractions x stiffnesses x
// dt x records x restoring models, each grid point a reference run (no delay) against a delayed
// run of an SDOF hybrid system.
//
// Inputs: a Study config (`sweep` block; the structure gives the damping, the integrator its kind,
// the substructuring the defaults). Empty sweep fields fall back to the study:
//   periods <- structure.sdof.period;  experimental_fractions <- substructuring.experimental_
//   fraction (0 there means 1: the paper's wholly experimental frame);  stiffnesses <- the
//   structure's mass or stiffness (mass 1 kg);  dts <- integrator.dt, else the record's dt;
//   motions <- study.motion;  models <- substructuring.model (linear).
// delay_model turns a delay tau (s) into a stage: SHIFT (default) u_r(t) = u(t - tau), EQ1 the
// paper's lead u + v tau, EQ1_LAG u - v tau, FIRST_ORDER a lag of time constant tau. tau = 0 means
// no stage.
//
// Per grid point (SI units): the reference is the purely numerical structure (alpha = 0) without
// delay; the delayed run splits the storey into (1 - alpha) k numerical and alpha k experimental
// behind the delay. Outputs: peak |u| of both (m), the paper's Eq. 2 as printed, NRMSE (%), peak
// error (m), and whether the delayed run diverged (then the error measures are inf).
//
// Grid order (index 0 first): motion, dt, model, stiffness, period, fraction, delay (innermost).
// Shard i of N holds the contiguous block of indices [i T / N, (i + 1) T / N), T = grid size.
// Linear SDOF cases with explicit Newmark and a shift (or no) delay run on the SIMD batch kernel
// (analysis/batch_kernel.h); everything else through core::simulate. Both agree to round-off,
// and a point's numbers do not depend on the shard or thread that computed it.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/ground_motion.h"
#include "rths/proto/config.pb.h"

namespace rths::analysis {

struct Shard {
  std::size_t index = 0, count = 1;  // 0-based slice index, number of slices
  std::string to_string() const;     // "i/N"
};
// Parses "i/N" with 0 <= i < N. Throws std::invalid_argument naming the text.
Shard parse_shard(const std::string& text);

struct SweepPoint {
  std::size_t index = 0;
  double period = 0, delay = 0, alpha = 0, stiffness = 0, dt = 0;  // s, s, -, N/m (0: mass 1 kg), s
  std::size_t motion = 0, model = 0;  // indices into SweepGrid::motion_names / model_names
};

struct SweepRow {
  SweepPoint point;
  double peak_reference = 0, peak_delayed = 0;  // m
  double eq2_paper = 0, nrmse_pct = 0, peak_error = 0;  // -, %, m (inf when diverged)
  bool diverged = false;  // analysis::compare: stopped, not finite, or grew past 10x the reference
};

class SweepGrid {
 public:
  // Expands and checks the sweep; loads and resamples every record. Throws std::invalid_argument
  // naming `source` and the field (unknown delay_model, no periods, a structure that is not an
  // SDOF, a dt beyond the integrator's limit at the shortest period, ...).
  SweepGrid(const config::Study& study, const std::filesystem::path& base_dir,
            const std::string& source);

  std::size_t size() const;
  SweepPoint point(std::size_t index) const;
  // [first, last) of a shard.
  std::pair<std::size_t, std::size_t> shard_range(const Shard& shard) const;

  // Hash of everything that defines the grid's numbers: the config (text format) and every
  // record's samples. Shards merge only with equal hashes.
  std::uint64_t hash() const { return hash_; }
  std::string hash_hex() const;

  const config::Study& study() const { return study_; }
  const std::filesystem::path& base_dir() const { return base_dir_; }
  const std::vector<double>& periods() const { return periods_; }
  const std::vector<double>& delays() const { return delays_; }
  const std::vector<double>& alphas() const { return alphas_; }
  const std::vector<double>& stiffnesses() const { return stiffnesses_; }
  const std::vector<double>& dts() const { return dts_; }
  const std::vector<std::string>& motion_names() const { return motion_names_; }
  const std::vector<std::string>& model_names() const { return model_names_; }
  const std::vector<config::RestoringForce>& models() const { return models_; }
  config::Sweep::DelayModel delay_model() const { return delay_model_; }
  // The record `motion` resampled to dts()[dt_index].
  const core::GroundMotion& motion_at(std::size_t motion, std::size_t dt_index) const;

 private:
  config::Study study_;
  std::filesystem::path base_dir_;
  std::vector<double> periods_, delays_, alphas_, stiffnesses_, dts_;
  std::vector<config::RestoringForce> models_;
  std::vector<std::string> motion_names_, model_names_;
  std::vector<std::vector<core::GroundMotion>> motions_;  // [motion][dt]
  config::Sweep::DelayModel delay_model_ = config::Sweep::SHIFT;
  std::uint64_t hash_ = 0;
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

// Rows of the shard, in index order.
std::vector<SweepRow> run_sweep(const SweepGrid& grid, const SweepOptions& options);

// --- CSV: a header (SI, the unit in every column name; NRMSE in percent) and the rows; what the
// rows are (grid hash, points, shard i/N) goes in a sidecar JSON, sweep_sidecar_path(csv), so the
// CSV itself is plain for any CSV reader. Numbers are written with 17 significant digits so
// merged shards equal an unsharded run byte for byte. Both files are written to a temporary file
// and renamed, so no half-written CSV looks complete.
// "sweep.csv" -> "sweep.meta.json".
std::filesystem::path sweep_sidecar_path(const std::filesystem::path& csv);
void write_sweep_csv(const std::filesystem::path& path, const SweepGrid& grid, const Shard& shard,
                     const std::vector<SweepRow>& rows);

struct SweepCsv {
  std::string grid_hash;
  std::size_t points = 0;
  Shard shard;
  std::string header;
  std::vector<std::size_t> indices;  // one per row, as in the file
  std::vector<std::string> lines;    // the rows' text
};
// Throws std::invalid_argument naming the file and line when it is not a sweep CSV.
SweepCsv read_sweep_csv(const std::filesystem::path& path);

// Joins shard CSVs into one complete CSV at `out`. Throws std::invalid_argument naming the
// files when they come from different grids, overlap (a duplicated index or shard), or leave
// indices missing. Returns the merged table.
SweepCsv merge_sweep_csvs(const std::vector<std::filesystem::path>& shards,
                          const std::filesystem::path& out);

// Rows parsed back from a sweep CSV (names of motion and model kept as text).
struct SweepTableRow {
  std::size_t index = 0;
  double period = 0, delay = 0, alpha = 0, stiffness = 0, dt = 0;
  std::string motion, model;
  double peak_reference = 0, peak_delayed = 0, eq2_paper = 0, nrmse_pct = 0, peak_error = 0;
  bool diverged = false;
};
std::vector<SweepTableRow> parse_sweep_rows(const SweepCsv& csv, const std::string& source);
std::vector<SweepTableRow> to_table(const SweepGrid& grid, const std::vector<SweepRow>& rows);

// Critical delay (s) of a period (s), fraction and dt (s); empty when stable for every delay.
using CriticalDelayOf = std::function<std::optional<double>(double period, double alpha, double dt)>;
// The critical delay of the grid's SDOF (study damping and integrator): core::check_critical_delay.
CriticalDelayOf critical_delay_of(const SweepGrid& grid);

// Two figures (PNG and SVG), at the first stiffness (the others coincide):
//   `png`: the paper's Fig. 4, NRMSE (%) against period on a log axis, one curve per delay (and per
//     model, fraction, dt and record when there are several), diverged points marked on a row above
//     the curves (they set no scale); below it the paper's Eq. 2 as printed.
//   sweep_delay_plot_path(png): NRMSE against delay (ms), one curve per period (at most 6, spread
//     over the range), with each period's critical delay drawn when `critical_delay` is given.
// Needs gnuplot.
void write_sweep_plot(const std::vector<SweepTableRow>& rows, const std::filesystem::path& png,
                      const std::string& title, const CriticalDelayOf& critical_delay = {});
// "out/sweep.png" -> "out/sweep_vs_delay.png".
std::filesystem::path sweep_delay_plot_path(const std::filesystem::path& png);

// The paper's claims, measured on the rows.
struct SweepTrends {
  // max over (period, delay, ...) of |e(k1) - e(k2)| / max|e| across stiffnesses (NRMSE); 0 when
  // only one stiffness was swept.
  double stiffness_max_relative_difference = 0;
  // Per delay > 0 series: fraction of consecutive period pairs where NRMSE falls (1 = monotone).
  double period_falling_fraction = 0;
  // Median over periods of NRMSE(non-linear model) / NRMSE(linear), when both were swept;
  // NaN otherwise. < 1: the softening model has the smaller delay error.
  double nonlinear_to_linear_median_ratio = 0;
  std::size_t diverged_points = 0;
};
SweepTrends measure_trends(const std::vector<SweepTableRow>& rows);

}  // namespace rths::analysis
