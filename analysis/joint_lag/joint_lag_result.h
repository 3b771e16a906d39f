#pragma once
// What the joint study (analysis/joint_lag/joint_lag.h) finds: its grid and across-sites points, each with
// its errors and measured lags, and the continuous stability boundary. Units SI (s, m).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace rths::analysis {

struct JointLagPoint {
  double network_round_trip = 0.0;  // s, injected
  double actuator_lag = 0.0;        // s, injected (time shift or time constant)
  // The errors against the lag-free reference (analysis/common/compare.h): E_peak and E_rms (%) lead,
  // the paper's NRMSE (relative) and Eq. 2 follow.
  double peak_error_pct = 0.0, rms_error_pct = 0.0;
  double nrmse = 0.0;  // relative
  double paper_eq2 = 0.0;
  double peak_error = 0.0;          // m
  double measured_total_lag = 0.0;  // s, J1 of realised behind command
  bool diverged = false;
  // Across sites only (zero otherwise):
  double measured_round_trip = 0.0;    // s, record median
  double measured_actuator_lag = 0.0;  // s, see deploy/joint_lag_sites.h
  bool real_time = false;              // the clock of the across-sites run
  double duration = 0.0;               // s of the record run across sites: its errors cover only
                                       // this stretch, so they are not comparable with the grid's
  bool past_boundary = false;  // network round trip beyond the critical one at this actuator lag
  // Across sites only: the in-process run of the lags the response can see, over the same
  // stretch (E_rms %, and the paper's relative NRMSE): network + actuator in real time; the
  // actuator alone in lockstep, which waits for every answer, so the network lag never reaches
  // the response.
  double in_process_rms_error_pct = 0.0;
  double in_process_nrmse = 0.0;
};

// Continuous stability boundary of the grid: for each actuator lag A, the network round trip R at
// which the loop (SDOF: m u'' + c u' + k_n u + k_e G_A(s) e^{-s R} u = 0, G_A the actuator model)
// first goes unstable: core::compensated_stability's continuous margin with the actuator model as
// the plant. Empty R: stable for every round trip.
struct BoundaryPoint {
  double actuator_lag = 0.0;                  // s
  std::optional<double> critical_round_trip;  // s
};

struct JointLagResult {
  std::string study_name;
  std::string actuator_model;
  std::vector<JointLagPoint> grid;      // network-major: all actuator lags for each round trip
  std::vector<JointLagPoint> measured;  // across sites
  std::string measured_skipped;         // why the across-sites part did not run, if it did not
  std::vector<BoundaryPoint> boundary;  // 0 .. largest actuator lag, finely spaced
  std::string boundary_skipped;         // why there is none (a structure with several storeys)
  // With a force predictor (JointLagStudy.force_predictor): the compensated loop's boundary at
  // the same actuator lags (from 0 to the largest where there is no plain boundary: several
  // storeys), R*(A) = D_p - A with D_p the critical lag of the measured pair, every link alike
  // (core::setup_loop_stability, the coupled loop with the model frozen at its initial error; an
  // actuator taken as a shift of its lag), and what it assumed; both empty without a predictor.
  // A boundary whose points all lack R: stable at every lag for that model error.
  std::vector<BoundaryPoint> compensated_boundary;
  std::string compensated_boundary_note;
  std::filesystem::path output_directory;
};

}  // namespace rths::analysis
