#pragma once
// Never silent on the response: the identified re-run's error (run_residual.h) against the floor a
// clean record of this rig would leave, and where it stands above that floor by more than a stated
// factor, what the record locates of it, whether or not a channel's residual holds it.
//
// Input: a run's identification (run_record.h) with its re-run.
//   error     E: the identified re-run's worst floor NRMSE (RunResidual::identified), at the DOF of
//             that floor; e(t) = u_identified(t) - u_recorded(t) there (m).
//   floor     F = max(RunResidual::noise_floor, kMinResponseFloor): the load cells' white noise
//             propagated through the identified re-run (the run's integrator received the noisy
//             reading, a re-run receives the model's force, so a clean record of this rig leaves
//             that much: clean records of the independent simulation and of the blind tune,
//             third and fifth sets leave 0.5-1.8 x it), and a stated relative
//             floor for a record with no noise (rths's own runs), whose re-run still leaves its
//             numerical resolution.
//   above     E > kResponseFloorFactor x F.
// Where above:
//   when      e's windows (locate.h residual_windows): those holding its power, with their share.
//   shape     e's spectral peak and the band of the middle 80 % of its power (residual_band); its
//             growth, the RMS of e over the record's last quarter / over its first; a slow trend
//             where a function of time (kRelationBins equal-count bins of t: the correlation ratio,
//             locate.h) explains at least kMinRelation of e's variance.
//   relation  the share of e's variance a function of the recorded displacement explains.
//   force     each actuator's force channel against its reported model (unexplained.h
//             prediction_without) without an offset drift (what the library's offset_drift would
//             hold, named or not): the residual's least-squares line over time. Where the line
//             explains at least kMinRelation of that residual's variance, it is said: its change
//             over the record (N) and, over the fitted stiffness, the displacement (m) the specimen
//             did not travel while the reading did, or a load cell that drifted (the force channel
//             alone does not tell them apart); with the share of e's variance a function of that
//             line explains.
//   silent    no description (unexplained.h), no channel above its floor and no event
//             (residual_floor.h): no channel explains it. Then a sensor the loop closes on is a
//             candidate: the loop follows its reading, so its error is invisible on its own channel
//             (the command -> displacement read channel reads as the model). Where the force
//             channel shows the slow part as well, the report's `unexplained` list holds one entry
//             on "displacement sensor N" (that actuator's), kinds ["time_varying"], `when` the
//             windows above.

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "identify/residual/locate.h"
#include "identify/run/run_record.h"

namespace rths::identify {

inline constexpr double kResponseFloorFactor = 10.0;
inline constexpr double kMinResponseFloor = 1.0e-4;  // worst floor NRMSE: a noise-free record's

// A force channel's slow part (response_floor.h force).
struct ForceTrend {
  int actuator = 0;          // 1-based
  double change = 0.0;       // N, the line's change over the record
  double as_travel = 0.0;    // m, change / the fitted stiffness; 0 without one
  double explained = 0.0;    // of the force residual's variance, by the line
  double of_response = 0.0;  // of e's variance, by a function of the line
};

struct ResponseFloor {
  double error = 0.0, floor = 0.0, noise_floor = 0.0;  // worst floor NRMSE
  int dof = 0;                                         // 1-based
  bool above = false;
  // Where above:
  std::vector<ResidualWindow> windows;
  ResidualBand band;
  double growth = 0.0;           // RMS over the last quarter / over the first
  double of_time = 0.0;          // of e's variance, by a function of time
  double of_displacement = 0.0;  // of e's variance, by a function of the recorded displacement
  std::vector<ForceTrend> force;
  bool silent = false;  // no channel's residual reported
  std::string text() const;
  nlohmann::json json() const;
  // The `unexplained` entry where silent and a force channel shows the slow part; else null.
  nlohmann::json unexplained_json() const;
};

// `run`'s re-run against its floor (above); none without a re-run.
std::optional<ResponseFloor> response_floor(const RunIdentification& run);

}  // namespace rths::identify
