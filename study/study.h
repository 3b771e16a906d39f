#pragma once
// Study configs: reading the Protobuf text format with errors that name file, line, column and
// field, and turning a config into core blocks (motion at dt, hybrid setup per case).
// Relative paths inside a config resolve against the config file's folder.

#include <filesystem>
#include <string>

#include "core/delay.h"
#include "core/ground_motion.h"
#include "core/simulation.h"
#include "core/substructure.h"
#include "rths/proto/config.pb.h"
#include "study/motion_config.h"
#include "study/recorders.h"
#include "study/restoring_force_config.h"

namespace rths::study {

// Every number of a study is checked against its range rule (study/ranges.h) by validate_study.

// Parses a text-format Study. Throws std::invalid_argument "FILE:LINE:COL: message" on unknown
// fields, wrong types or syntax errors, and on semantic errors (negative period or delay, both
// experimental_fraction and experimental_storeys, ...) naming the field.
config::Study load_study(const std::filesystem::path& path);
config::Study parse_study(const std::string& text, const std::string& source_name);

// Checks the semantic rules above and the bounds; throws std::invalid_argument naming the field.
// Unique case names; every number inside its range (study/ranges.h): lags <= 1 s unless
// allow_long_lag, dt in [1 us, 1 s] (0 = the record's), periods in (0, 50] s, counts >= 1, the
// deployment's timeouts > 0 (0 = default), loop_cpu a CPU of this machine.
void validate_study(const config::Study& study, const std::string& source_name);
// One link's injected lag: delay and jitter by the lag rule, loss a probability in [0, 1); its
// network emulation: drift_rate a fraction (s per s), spike_delay by the lag rule, spike_every,
// spike_steps, drop_first_step and drop_steps counts (0 = off), spike_steps < spike_every.
// Throws std::invalid_argument "SOURCE: WHERE.field = ...".
void validate_link_lag(const config::LinkLag& lag, const std::string& where, bool allow_long_lag,
                       const std::string& source);

std::unique_ptr<core::DelayStage> make_delay_stage(const config::DelayStage& stage, double dt,
                                                   const std::filesystem::path& base_dir);
core::DelayChain make_delay_chain(
    const google::protobuf::RepeatedPtrField<config::DelayStage>& stages, double dt,
    const std::filesystem::path& base_dir);

// Relative matrix files (structure.matrices) resolve against base_dir.
core::StructuralModel make_structure(const config::Structure& structure,
                                     const std::filesystem::path& base_dir = {});
core::IntegratorKind integrator_kind(const config::Integrator& integrator);
// The inverse: the config kind of a core integrator (every core kind has one).
config::Integrator::Kind config_integrator_kind(core::IntegratorKind kind);

// A study made ready to run: the motion resampled to the step, the structure and the partition.
struct PreparedStudy {
  config::Study config;
  std::filesystem::path base_dir;
  core::GroundMotion motion;  // at dt
  core::HybridSetup base;     // no delay stages
  // What the config most likely did not mean but is allowed (a grounded specimen that reads as a
  // storey): each program prints them before it runs.
  std::vector<std::string> warnings;
  // What each case keeps and writes (study/recorders.h), checked against the model.
  RecorderPlan recorders;
};
PreparedStudy prepare_study(const config::Study& study, const std::filesystem::path& base_dir);

// What a study fixes before any motion or case: structure, integrator, dt (s), partition and the
// servo loop. The one construction in-process runs and distributed nodes share. Relative matrix
// files resolve against base_dir. A structure given by matrices is split at its experimental DOFs
// (study/structure_config.h): the model's mass and damping are then the numerical part's.
core::HybridSetup base_setup(const config::Study& study, double dt,
                             const std::filesystem::path& base_dir = {},
                             std::vector<std::string>* warnings = nullptr);
// Servo periods per integrator step from study.servo.rate (Hz) and dt (s): 1 when unset; throws
// std::invalid_argument naming servo.rate unless rate * dt is a whole number in [1, 64].
int servo_substeps(const config::Study& study, double dt);
constexpr int kMaxServoSubsteps = 64;

// The base setup with the case's delay stages on every actuator, behind the case's compensation.
core::HybridSetup setup_for_case(const PreparedStudy& prepared, const config::Case& study_case);

// Puts compensation `blocks` in front of the delay chains of `actuators` (indices into
// setup.delays), built at the servo period: one block for all of them, or one per actuator, in
// order. No blocks: nothing changes. Throws std::invalid_argument naming `where` when the count
// fits neither rule, a block is bad, or an actuator already has a compensator (one compensator per
// actuator, given in one place: the case's or its emulator node's).
// The case's force predictor (core/force_predictor.h) on the actuators it names, each started at
// its specimen's initial stiffness times stiffness_factor, its shape the block's model when
// given (at that initial stiffness), else the specimen's. Throws std::invalid_argument opening
// with `where` and naming the field when out of range or an actuator does not exist.
void apply_force_predictor(core::HybridSetup& setup, const config::ForcePredictor& block,
                           const std::string& where);
// The one range rule of a ForcePredictor block (dt: the integrator's step, 0 when not yet known).
void validate_force_predictor(const config::ForcePredictor& block, double dt,
                              const std::string& where);
// The predictor's starting model stiffness relative to the declared specimen's: the block's
// stiffness_factor, unset (0) = 1. The one place its default is read.
double predictor_stiffness_factor(const config::ForcePredictor& block);
// The block's parameters for a specimen whose declared initial stiffness is `declared_stiffness`.
core::PredictorParameters predictor_parameters(const config::ForcePredictor& block,
                                               double declared_stiffness);
void apply_compensation(core::HybridSetup& setup, const std::vector<int>& actuators,
                        const google::protobuf::RepeatedPtrField<config::Compensation>& blocks,
                        const std::string& where);

// The case named `reference_case`, else the first. Throws if there are none.
const config::Case& reference_case(const config::Study& study);
// The case named `name`, or the reference case when `name` is empty: nullptr when no case has
// that name (case_named), std::invalid_argument naming it (find_case). Every command, node and
// reader finds a study's case this one way.
const config::Case* case_named(const config::Study& study, const std::string& name);
const config::Case& find_case(const config::Study& study, const std::string& name);

}  // namespace rths::study
