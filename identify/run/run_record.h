#pragma once
// A distributed run identified from its record (`rths identify RECORD.rthsrec`), read through the
// project's one record reader (runtime read_record + measure_run), against the run's own config
// (the record header's study: the declared model).
//
// Per link (node): the network path (network_path.h), declared = the node's receive_lag +
// send_lag in the header's deployment.
// Per actuator a (1-based): the actuator path, command -> measured displacement, and the
// specimen, measured displacement -> force, identified by identify.h with the effect library;
// declared = the case's delay stages (shift -> delay, first_order -> first_order, a second-order
// transfer function -> second_order, backlash -> backlash, velocity_limit ->
// velocity_saturation, stroke_limit -> stroke_limit, each with the config's value as initial
// value), gain = the stages' amplitude gain; no stage at all declares a delay of 0 (the commands
// reach the rig at once). Undeclared effects: the steps the search added that
// removed more than kMinErrorRemoved of held-out error when added and still do in the final model
// (refitted without it), and a fitted gain off the declared one by more than kGainTolerance (an
// emulator gain error), and a fitted delay off the declared one (kDelayTolerance). A run that
// diverged is identified up to the last step whose response is finite and below the coordinator's
// divergence bound; a truncated record (no footer, or a cut last entry) is identified from what it
// holds; both say so (`held`). The system-level residual re-runs the study over the same steps,
// from the record's own ground acceleration (run_residual.h). The findings (findings.h) and each
// channel's effect estimates are computed here once; run_record_format.h prints them. An effect
// the form-free description of its channel's residual beats on held-out data is not named, and
// what each channel's model leaves is described (unexplained.h) before the re-run, which gives
// each description its share of the response error. A named effect whose magnitude fits badly
// (plausibility.h: poorly determined, implausible) is rejected with its reason before the re-run,
// which holds a parameter that moved by its fitted shape where that helps on held-out steps
// (run_residual.h moving). Which node
// answered for which actuator or storey comes from runtime::answer_sources, the planning the
// coordinator ran (platform_replay.h). Bad input -> std::invalid_argument
// "RECORD: ENTRY: PROBLEM": a record that cannot be read or has damaged entries (the reader's loss
// report names them), a header of another schema version, no header, a link the header lists with
// no answer, fewer steps than identification needs.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "identify/fit/identify.h"
#include "identify/run/actuator_path.h"
#include "identify/run/findings.h"
#include "identify/run/network_path.h"
#include "identify/run/platform_replay.h"
#include "identify/run/residual_floor.h"
#include "identify/run/run_residual.h"
#include "identify/run/unexplained.h"
#include "runtime/record/deadline_diagnosis.h"

namespace rths::identify {

inline constexpr double kGainTolerance = 0.02;  // relative
// A fitted delay off the declared one by more than this share of it, and by more than a quarter
// of the run's step, is named "delay change" (e.g. a network lag that reached the actuator path
// of a real-time run).
inline constexpr double kDelayTolerance = 0.05;
// An added effect is named only when it removes at least this much held-out error (a share of
// the signal's std): the record of a simulated run has no sensor noise, and below this a relative
// fall of the error is round-off, not an effect.
inline constexpr double kMinErrorRemoved = 1.0e-4;

struct RunIdentification {
  std::string record, clock, case_name;
  std::size_t steps = 0;  // identified
  double duration = 0.0;  // s
  std::string held;       // how much the record held: complete, truncated, diverged
  std::string inputs;     // where the re-run's inputs came from (study::inputs_source)
  config::Study study;    // the run's own config (the record header's)
  // Real time: why steps missed their deadlines and what the record is worth for it (said first:
  // a response dominated by overruns is the platform's as much as the rig's); absent in lockstep.
  std::optional<runtime::DeadlineDiagnosis> platform;
  // Which answer each step used (platform_replay.h): the actuator paths are identified on the
  // answers at the steps they answer, and the re-run replays the schedule.
  std::optional<PlatformReplay> replay;
  std::vector<NetworkPath> links;
  std::vector<ActuatorPath> actuators;
  // The study re-run with the declared and the identified actuators (run_residual.h); absent
  // when the actuator channel was not identified.
  std::optional<RunResidual> residual;
  // Whether the re-run tries moving parameters (run_residual.h ResidualInput::hold_moving).
  bool hold_moving = true;
  // Every difference from the declared config, every part, computed once (findings.h): what the
  // report (run_record_format.h) prints and the JSON holds.
  std::vector<Finding> findings;
  // What each channel's identified model leaves, described without presuming an effect
  // (unexplained.h), with its share of the re-run's remaining error: one line each.
  std::vector<Unexplained> unexplained;
  // Every identified channel's held-out residual against its floor (residual_floor.h): where one
  // is above it, where, when and at what frequencies; the report says "none" only at the floor.
  std::vector<ChannelFloor> floors;
};

RunIdentification identify_run_record(const std::filesystem::path& record,
                                      const IdentifyOptions& options);

// The re-run keeps only what helps: while a named effect (ActuatorPath::undeclared,
// specimen_undeclared) makes `run`'s re-run worse, its removal (run_residual.h effects) below
// -kMinErrorRemoved, the worst one is rejected (moved to its path's `rejected` with the NRMSE it
// added, so that rig_models leaves it out of the re-run and the written study) and
// `run.residual` made again by `rerun` (the study re-run with the paths as they stand). One
// effect per pass: it ends within as many passes as effects named. identify_run_record calls it
// before the findings are collected; nothing to do without a residual.
// The re-run never ends worse than the declared model: where the identified re-run's worst-floor
// NRMSE over the whole record is still above the declared one's by more than kMinErrorRemoved,
// every named effect is taken out (and no parameter held moving), then each is put back, in the
// order named, only where it lowers that whole-record error by more than kMinErrorRemoved, and
// the moving parameters last on the same rule; the ones left out are rejected with that reason
// and the residual's notes say the re-run fell back (the held-out steps that choose a moving
// parameter and the removals above can disagree with the whole record, which is what is reported).
void keep_what_helps(RunIdentification& run, const std::function<RunResidual()>& rerun);

// True for a path named *.rthsrec (what `rths identify` reads as a run record).
bool is_run_record(const std::filesystem::path& path);

}  // namespace rths::identify
