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
//   error            nrmse(u_ref, u) = sqrt(mean e^2) / median|u_ref|, and the paper's Eq. 2
//   measured total   J1 delay of the realised behind the commanded displacement (cross-correlation
//                    peak, s), compared with injected = R + A.
// Measured across sites (optional, needs namespaces): selected points run across network-namespace
// sites with the clock of the sites config, R injected half each way by the actuator emulator, the
// actuator lag as the case's delay stage; from the record:
//   real time  the coordinator uses the newest feedback it has, so the realised displacement it
//              records lags the command by round trip + actuator lag: total = J1(command,
//              realised); network = round-trip median; actuator = their difference.
//   lockstep   each command is paired with its own answer: actuator = J1, network = round-trip
//              median, total = their sum. (The result itself sees only the actuator lag.)
// Error against the in-process reference over the same duration.
//
// Stability (SDOF studies): before the grid runs, the continuous boundary R*(A) (BoundaryPoint);
// grid points past it are flagged (past_boundary) and a warning names how many.
//
// Outputs (in the output directory): grid.csv, measured.csv (nrmse_pct: the one NRMSE convention,
// a percentage), error_map.png and .svg (2-D heat map of NRMSE %, log colour scale, contour lines,
// the stability boundary, diverged points marked), total_lag.png and .svg (measured vs injected),
// summary.json.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rths/deploy/joint_lag.pb.h"

namespace rths::deploy {

struct JointLagPoint {
  double network_round_trip = 0.0;  // s, injected
  double actuator_lag = 0.0;        // s, injected (time shift or time constant)
  double nrmse = 0.0;               // relative
  double paper_eq2 = 0.0;
  double peak_error = 0.0;          // m
  double measured_total_lag = 0.0;  // s, J1 of realised behind command
  bool diverged = false;
  // Across sites only (zero otherwise):
  double measured_round_trip = 0.0;  // s, record median
  double measured_actuator_lag = 0.0;  // s, see above
  bool real_time = false;              // the clock of the across-sites run
  bool past_boundary = false;          // network round trip beyond the critical one at this actuator lag
};

// Continuous stability boundary of the grid: for each actuator lag A, the network round trip R at
// which the loop (SDOF: m u'' + c u' + k_n u + k_e G_A(s) e^{-s R} u = 0, G_A the actuator model)
// first goes unstable: core::compensated_stability's continuous margin with the actuator model as
// the plant. Empty R: stable for every round trip.
struct BoundaryPoint {
  double actuator_lag = 0.0;                     // s
  std::optional<double> critical_round_trip;     // s
};

struct JointLagResult {
  std::string study_name;
  std::string actuator_model;
  std::vector<JointLagPoint> grid;      // network-major: all actuator lags for each round trip
  std::vector<JointLagPoint> measured;  // across sites
  std::string measured_skipped;         // why the across-sites part did not run, if it did not
  std::vector<BoundaryPoint> boundary;  // 0 .. largest actuator lag, finely spaced
  std::string boundary_skipped;         // why there is none (a structure with several storeys)
  std::filesystem::path output_directory;
};

JointLagStudy load_joint_lag(const std::filesystem::path& path);

struct JointLagOptions {
  std::optional<std::filesystem::path> output_directory;  // overrides the config's
  bool measure = true;       // run the across-sites part when the config asks and it is possible
  bool plots = true;
  // Called after each grid point and each across-sites run: done of total (both counted).
  std::function<void(std::size_t done, std::size_t total)> progress;
};

JointLagResult run_joint_lag(const JointLagStudy& config, const std::filesystem::path& base_dir,
                             const JointLagOptions& options);

// Writes the CSVs, summary.json and (if plots) the PNGs into result.output_directory.
void write_joint_lag_outputs(const JointLagResult& result, bool plots);

nlohmann::json to_json(const JointLagResult& result);
std::string to_text(const JointLagResult& result);

}  // namespace rths::deploy
