#pragma once
// The system-level residual of a distributed run: the study re-run in process (core::simulate)
// with the record's own config, once with the declared model and once with the identified one,
// each response against the recorded response.
//
// Inputs: the run's study and case (the record header), the ground acceleration of every step
// the record holds (m/s^2, the coordinator's own samples, so the motion file is not needed), the
// recorded displacement (m, steps x DOFs) and the actuator paths identified from the record
// (run_record.h), in the order of the record's actuators.
// Declared model of actuator a: the case's delay stages behind the actuator emulators' own
// declared receive_delay stages (what the distributed run applies to a command), with the case's
// compensation in front. Identified model: the identified actuator as study stages
// (sensors.h rig_models as study_config.h actuator_case with the rig: shift, first order, second
// order, backlash, velocity and stroke limits with the gain, the displacement sensor's drift and
// scale) in place of those delay stages,
// the compensation kept; where the force channel contradicted the declared specimen
// (ActuatorPath::specimen_undeclared), the identified storey model in place of the declared one
// (specimen_model, at its identified initial stiffness), what its load cell reads beside it as
// force stages (study_config.h add_force_stages: damping as viscous_force, coulomb_friction as
// friction_force, inertia as inertia_force, the force channel's delay as force_delay) and the load
// cell's drift as a sensor_drift stage.
// Errors, per recorded DOF i (a column of the record: every DOF, or those the recorders kept,
// RunHeader.recorded_dofs): NRMSE_i = sqrt(mean (u_sim - u_rec)^2) / median |u_rec| (core/metrics.h
// nrmse, the record as reference) over the steps both responses hold, u_sim the re-run's u of the
// same DOF; a re-run keeps the recorded DOFs only (core::SimulationOptions::kept_dofs).
// Which link explains how much: the error measure E is the worst floor's NRMSE.
//   per actuator link a   E(declared) - E(only actuator a identified): the error it removes;
//   per undeclared effect E(identified without the effect) - E(identified): the error the effect
//                         removes on top of the rest ("gain error", "delay change", "stiffness
//                         change": the value set back to the declared one; any other: the effect
//                         taken out of the model; "scale": the sensor reading true), on its part
//                         (sensors.h part_of): "actuator a", "displacement sensor a", "specimen a"
//                         or "load cell a". A sensor's noise is not re-run.
// An undeclared specimen effect the re-run cannot hold (a cubic stiffness, a time-varying one:
// no storey model or force stage holds them) has no removal: the notes name it with the reason.
// Each removal's share is its error removed over the sum of the positive ones of its kind.
// The platform's share (a real-time record whose steps used older answers: platform_replay.h):
// the identified re-run replays the answers the loop used (core::AnswerReplay), and
//   platform              E(identified, every step on its own answer) - E(identified): the error
//                         the late answers and overruns made, beside the actuator links in `links`.
// What a channel's described residual accounts for (unexplained.h): the identified re-run with the
// residual the description gives put back where the channel reads it (the force channel's added
// to the force the integrator receives, the measured channel's to the actuator's motion, linear
// in time between the record's samples):
//   described             E(identified) - E(identified + the channel's described residual), and
//                         its share of E(identified) (not of the removals).
// A parameter that moved over the run (moving_parameter.h: a time-varying stiffness, gain or
// delay a channel named) is held moving only where that helps on data the fit did not see: the
// identified re-run with it and with its constant, each scored by the worst floor's NRMSE over
// the steps its channel's identification held out (Identification::split.heldout), in the order
// named, each on top of those kept before; kept when moving leaves less by kMinMovingGain
// (moving). A kept one is in the identified re-run, and its removal is the re-run without it.
// The figures reported for it are those same held-out steps' (the choice was made on them, so
// they are not an independent test of it): the report and the JSON say so.
// The declared re-run and each link's "all" run are not replayed: the declared model is what the
// lab planned, on time. A network path's lag reaches the response only through the answers the
// loop used, so the replay is its part of the re-run; in lockstep it does not reach it.

#include <filesystem>
#include <string>
#include <vector>

#include "core/ground_motion.h"
#include "core/simulation.h"
#include "identify/run/moving_parameter.h"
#include "identify/run/platform_replay.h"
#include "rths/proto/config.pb.h"

namespace rths::identify {

struct ActuatorPath;
struct Unexplained;

inline constexpr double kMinMovingGain = 1.0e-4;  // NRMSE of the worst floor, held-out steps
inline constexpr unsigned kNoiseFloorSeed = 62;   // the noise floor's draw (noise_floor)

struct FloorError {
  int dof = 0;                              // 1-based, the DOF the record's column holds
  double declared = 0.0, identified = 0.0;  // NRMSE against the record
};

struct ResidualShare {
  std::string link;      // "actuator 1", "specimen 1", "load cell 1", "displacement sensor 1",
                         // "platform"
  std::string effect;    // "all" (the link's whole identified model) or the effect's name
  double removed = 0.0;  // NRMSE of the worst floor removed by it
  double share = 0.0;    // of the removals of its kind
};

// A moving parameter tried in the re-run: the worst floor's NRMSE over the held-out steps with
// its constant and with it moving, and whether it was kept (decided on those same steps).
struct MovingRerun {
  MovingParameter parameter;
  double constant = 0.0, moving = 0.0;
  bool kept = false;
};

struct RunResidual {
  std::size_t steps = 0;                    // compared
  std::vector<FloorError> floors;           // one per column of the record, in its order
  double declared = 0.0, identified = 0.0;  // the worst floor's NRMSE
  bool declared_diverged = false, identified_diverged = false;
  std::vector<ResidualShare> links, effects;
  // Per described channel (link: its part, effect: its channel word); share of `identified`.
  std::vector<ResidualShare> described;
  std::vector<MovingRerun> moving;  // every moving parameter named, kept or not
  // The re-run floor: the worst floor's NRMSE (against the record's median |u|) by which the
  // identified re-run moves with each load cell's white noise (ActuatorPath::force_noise) put
  // back where the integrator receives the force, one seeded draw: what a clean record of this
  // rig leaves, since the run's integrator received the reading and the re-run the model's force
  // (response_floor.h). 0 without a load cell's noise.
  double noise_floor = 0.0;
  std::vector<std::string> notes;  // stages left out of the re-run, network paths
  std::string platform;            // the replayed answers (PlatformReplay::text); empty: none
  // The responses compared (steps x recorded DOFs, m; column i is floors[i]'s DOF) at `time`
  // (s): for plots.
  std::vector<double> time;
  core::Mat recorded_response, declared_response, identified_response;
};

// The case as the distributed run applied it to a command: the actuator emulators' declared
// receive_delay stages, then the case's delay stages (its compensation and name kept).
config::Case declared_case(const config::Study& study, const config::Case& study_case);

struct ResidualInput {
  const config::Study* study = nullptr;
  std::string case_name, clock;
  // The record's folder: a study written before records carried their inputs names its matrix
  // files relative to it (one rule: a file named is relative to the file that names it).
  std::filesystem::path base_dir;
  core::GroundMotion motion;            // at the run's dt, one sample per recorded step
  const core::Mat* recorded = nullptr;  // m, steps x recorded DOFs (at least motion's steps)
  // The DOF (0-based, ascending) each column of `recorded` holds (runtime::recorded_dofs); empty:
  // column i holds DOF i.
  std::vector<int> recorded_dofs;
  const std::vector<ActuatorPath>* actuators = nullptr;
  const PlatformReplay* platform = nullptr;  // null or no late step: every step on its own answer
  const std::vector<Unexplained>* unexplained = nullptr;  // null: none described
  // False: no parameter is tried moving (the re-run fell back to the declared model and adds a
  // moving one back only where it lowers the whole record's error: run_record.h keep_what_helps).
  bool hold_moving = true;
};

// Throws std::invalid_argument when the study cannot be set up (naming the config's field).
RunResidual run_residual(const ResidualInput& input);

// A ratio as the run's reports print it: 0.672 -> "67.2 %" (3 significant digits).
std::string percent_text(double ratio);

}  // namespace rths::identify
