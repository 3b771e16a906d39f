#pragma once
// One comparison of a case with its reference, used by every command that reports an error
// against a reference (run, sdof, sweep; launch, joint-lag and identify's predict should call it).
//
// The response is named explicitly (ResponseSpec): one floor's displacement relative to the
// ground, or every floor with the worst value over floors kept ("peak over floors").
// Over the steps both histories have (a diverged case stops early), e = u - u_ref:
//   peak_error_pct        E_peak = 100 max|e| / max|u_ref|        (%; the benchmark's J3 and J5
//                         form): the headline error, read as "the worst miss, in % of the peak"
//   rms_error_pct         E_rms = 100 sqrt(sum e^2 / sum u_ref^2)  (%; the J2 and J4 form without
//                         the mean removed): the typical miss against the typical response
//   nrmse_pct             100 sqrt(mean e^2) / median|u_ref|        (%, the paper's normalisation
//                         made N-independent; a record that ends in seconds of near-zero motion
//                         has a tiny median and inflates it: kept for the paper's Fig. 4, not led
//                         with)
//   paper_eq2_as_printed  sqrt(sum e^2) / N / median|u_ref|         (the paper's Eq. 2, literal)
//   peak_error_m          max |e|;  peak_reference_m, peak_m  max |u| of each (m)
// reference_steps: the reference's length. A case with fewer steps (it stopped early) has no error
// over the steps it did not run: covers_reference() is false and a report shows its errors as
// over steps_compared of reference_steps, or "-", never as a result for the whole record.
//   diverged              the case stopped early, is not finite, or its peak grew past
//                         core::kDivergenceGrowth times the reference's
//                         (core::grew_past_reference).
// Judge divergence against the lag-free reference; a lagged reference hides growth.

#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/simulation.h"

namespace rths::analysis {

class ResponseSpec {
 public:
  // Floor n, 1-based (1 = first floor; an SDOF has only floor 1).
  static ResponseSpec floor(int one_based);
  // The top floor of a structure with `floors` floors.
  static ResponseSpec top_floor(int floors) { return floor(floors); }
  // Every floor; each metric is the worst over floors.
  static ResponseSpec peak_over_floors() { return ResponseSpec(0); }

  bool is_floor() const { return floor_ > 0; }
  int floor_number() const { return floor_; }  // 0 for peak over floors
  // "floor 3", "peak over floors".
  std::string describe() const;
  // The floors (0-based DOF columns) this spec reads from a result with `dofs` columns. Throws
  // std::invalid_argument when the floor does not exist.
  std::vector<int> columns(int dofs) const;

 private:
  explicit ResponseSpec(int floor) : floor_(floor) {}
  int floor_;
};

struct Comparison {
  std::string response;  // ResponseSpec::describe()
  std::size_t steps_compared = 0;
  double peak_reference_m = 0.0, peak_m = 0.0, peak_error_m = 0.0;
  double peak_error_pct = 0.0, rms_error_pct = 0.0;
  double nrmse_pct = 0.0, paper_eq2_as_printed = 0.0;
  std::size_t reference_steps = 0;
  bool diverged = false;
  bool covers_reference() const { return steps_compared >= reference_steps; }
  nlohmann::json to_json() const;
};

// Displacement history of one floor (m), its DOF 0-based. Throws std::invalid_argument naming
// the DOF when the run did not keep it (SimulationResult::dofs).
std::vector<double> floor_history(const core::SimulationResult& result, int dof);
// Column `column` (0-based) of any per-step history (one row a step), e.g. an actuator's command.
std::vector<double> column_of(const core::Mat& history, int column);

// Compares histories sampled at the same step. `stopped_early` marks a case the simulation
// stopped (its own divergence guard or a limit): it counts as diverged.
Comparison compare(std::span<const double> reference, std::span<const double> result,
                   bool stopped_early);
Comparison compare(const core::SimulationResult& reference, const core::SimulationResult& result,
                   const ResponseSpec& response);

// `rths run`'s verdict beyond the 10x rule of compare(): a run past its critical delay whose
// envelope grows exponentially over its last cycles of `period` (s; the governing mode's), u
// sampled at dt (s), is diverging (core::envelope_growth, EnvelopeGrowth::grows). False when not
// past, or when the record is too short to fit.
bool diverging(std::span<const double> u, double dt, double period, bool past_critical_delay);

}  // namespace rths::analysis
