#pragma once
// The grid of the paper's Fig. 4 study: periods x delays x experimental fractions x stiffnesses x
// dt x records x restoring models, each grid point a reference run (no delay) against a delayed
// run of an SDOF hybrid system (analysis/sweep/sweep_run.h runs it, sweep_csv.h writes and merges it,
// sweep_report.h plots it and measures the paper's trends on it).
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
// Grid order (index 0 first): motion, dt, model, stiffness, period, fraction, delay (innermost).
// Shard i of N holds the contiguous block of indices [i T / N, (i + 1) T / N), T = grid size.

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
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

}  // namespace rths::analysis
