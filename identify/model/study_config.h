#pragma once
// The identified model as study-config parts (proto/config.proto), so that `rths run` simulates
// a planned test with this lab's actuator and specimen.
//
// Actuator (channel `measured`) -> a Case whose delay stages are, in order:
//   shift { delay } with amplitude_gain = gain (omitted when 1), first_order { time_constant },
//   transfer_function wn^2 / (s^2 + 2 zeta wn s + wn^2) for a second-order lag.
//   A time-varying delay enters with its mean; offset/drift, backlash, velocity saturation and the
//   stroke limit are lab-scale effects (mm of this rig) that do not scale to another structure:
//   listed in `left_out`, unless the case is for the rig itself (`rig` below).
// Specimen (channel `force`) -> the storey RestoringForce that has the same shape (the study's
// structure supplies the initial stiffness k0; the identified k0 is reported beside it):
//   stiffness k alone                  linear {}                                   k0 = k
//   k d + F_bw z (Bouc–Wen, n = 1)     bouc_wen { yield_displacement d_y, alpha k / k0, n 1,
//                                                 beta 0.5 }                        k0 = k + F_bw / d_y
//   k d + p (elasto-plastic k_p, F_y)  bilinear { yield_displacement F_y / k_p,
//                                                 post_yield_ratio k / k0 }        k0 = k + k_p
//   (core/restoring_force.h: f = alpha k0 u + (1 - alpha) k0 z with z in m, which is the
//   identified F_bw z' with z' = z / d_y.) Velocity terms (damping, friction), mass, cubic
//   stiffness, drifts, offsets and the force delay have no place in a storey model: `left_out`
//   (each saying whether a force stage holds it: add_force_stages).
//   A specimen with no displacement-dependent force (a pure damper) gives no RestoringForce.
// Fragment (study_fragment, written with study::write_text_format): a text-format Study holding only
//   substructuring { model { ... } } and cases { name: "identified_actuator" ... },
// the parts to copy into a study. identified_study() puts them into a whole study: the base's
// model replaced, the case appended, relative paths of the base (motions, the cases' and the
// nodes' traces) made absolute, so the result can
// be written anywhere and run with `rths run`.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "identify/model/model.h"
#include "rths/proto/config.pb.h"

namespace rths::identify {

inline constexpr const char* kIdentifiedCaseName = "identified_actuator";

struct ActuatorCase {
  config::Case study_case;
  std::vector<std::string> left_out;
};
// @pre actuator.channel == Channel::kMeasured (throws std::invalid_argument otherwise).
// The record a rig was measured in, for re-running that rig as it was (identify/run): its
// first sample's time and its length (s), the time base of a fitted offset drift
// (offset + drift (t - t_mid) / duration, t_mid its middle).
struct RigRecord {
  double start = 0.0, duration = 1.0;
};
// A fitted offset + drift s (s = (t - t_mid) / duration over the record) as offset + rate t:
// {offset at t = 0, rate per second}.
std::pair<double, double> drift_in_time(double offset, double drift, const RigRecord& rig);
// With `rig`, the rig's own effects are stages too (core/rig_effects.h): backlash { width },
// velocity_limit { max_velocity }, stroke_limit { stroke } after the linear stages, the gain on the
// last of them (the model's order: gain after the non-linearities), and an offset drift of the
// displacement sensor as sensor_drift { displacement_offset, displacement_drift } at the end.
ActuatorCase actuator_case(const ChannelModel& actuator, const SignalScales& scales,
                           const std::string& name = kIdentifiedCaseName,
                           const std::optional<RigRecord>& rig = std::nullopt);
// What the load cell of a fitted specimen (channel force) reads beyond its storey model, as the
// case's force stages (core/rig_effects.h), each with the fitted value:
//   damping (N s/m)                               viscous_force { damping }
//   coulomb (friction_force N, smoothing_velocity  friction_force { friction_force,
//   m/s: F_c tanh(v / v_s))                          smoothing_velocity }
//   inertia (mass kg: m a)                         inertia_force { mass }
//   delay (s: the force channel's shift)           force_delay { delay }
// in that order, after every stage that moves the specimen and before the sensor_drift stages
// that end the case (the fitted model adds the load cell's offset after the shift), and the load cell's offset drift as a sensor_drift stage's force
// fields (N, N/s of simulated time), merged into the case's sensor_drift stage (appended when it
// has none). `held`: effects the case's stages already hold (a declared tracking loop's specimen
// inertia and damping, its load cell's delay), not added again. Nothing for a specimen with none.
void add_force_stages(const ChannelModel& specimen, const SignalScales& scales,
                      const RigRecord& rig, config::Case& study_case,
                      const std::vector<Effect>& held = {});
// Whether `stage` is one of the force stages above (it passes the displacement unchanged).
bool is_force_stage(const config::DelayStage& stage);
// The force stages of `declared` (a case whose stages the identified actuator replaces) put into
// `study_case` as add_force_stages places them: what the record did not contradict of the
// specimen's load cell stays when the actuator's stages are replaced.
void keep_declared_force_stages(const config::Case& declared, config::Case& study_case);
// Whether add_force_stages holds a specimen effect (damping, coulomb, inertia, the force
// channel's delay, offset_drift): what a storey model leaves out but the re-run still holds.
bool held_by_force_stages(Effect effect);
// A displacement sensor reading `scale` x the truth (identify/run/sensors.h) as the case's
// sensor_drift stage's displacement_scale, merged into that stage (appended when it has none).
// Nothing for a scale of 1.
void add_displacement_scale(double scale, config::Case& study_case);

struct SpecimenModel {
  std::optional<config::RestoringForce> restoring_force;
  double initial_stiffness = 0.0;  // N/m, k0 of the identified specimen
  std::string description;
  std::vector<std::string> left_out;
};
// @pre specimen.channel == Channel::kForce (throws std::invalid_argument otherwise).
SpecimenModel specimen_model(const ChannelModel& specimen, const SignalScales& scales);

// A Study holding only the parts above (either may be absent).
config::Study study_fragment(const std::optional<ActuatorCase>& actuator,
                             const std::optional<SpecimenModel>& specimen);

// `base` (read from a file in base_dir) with the fragment's storey model and cases: the model
// replaces the base's, the cases are appended. Throws std::invalid_argument when a case name
// is already in the base. Named "<base name>_identified", with no output directory of its own.
config::Study identified_study(const config::Study& base, const std::filesystem::path& base_dir,
                               const config::Study& fragment);

}  // namespace rths::identify
