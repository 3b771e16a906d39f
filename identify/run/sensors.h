#pragma once
// What a run's record says of its sensors, beside the actuator and the specimen: each channel's
// noise, and a displacement sensor whose scale is off. Both are judged on one actuator path
// (actuator_path.h) after its channels were identified.
//
// Noise. The estimate is the white part of the channel's residual r = target - the final model's
// prediction at the full rate: the step r_{j+1} - r_j of a white Gaussian noise is N(0, 2 sigma^2),
// so sigma^2 = median((r_{j+1} - r_j)^2) / (2 x 0.4549), 0.4549 the median of a chi-square of one
// degree of freedom. A model error that is smooth over a sample hardly reaches it, and the median
// leaves out a few samples the model does not hold (the first answer of a run, a velocity
// limit's corners), which a mean and a spectral floor (which also counts the signal's own tail
// above its band) take for noise. sigma_d (m) on the displacement sensor, sigma_f (N) on the load
// cell (the specimen model runs on the low-passed displacement, so the displacement's noise stays
// out of it); its statistical half-width about sigma sqrt(2 / n) for n samples. The declared noise
// is the case's tracking loop's (displacement_noise_rms, force_noise_rms) with its converter's
// quantisation, q / sqrt(12), 0 when the case declares none. Noise is named ("noise" on
// "displacement sensor N" or "load cell N") when it is above kNoiseShare of the signal's std (a
// signal-to-noise ratio below 40 dB, where a lab would look at the sensor) and above
// kNoiseAboveDeclared x the declared. It is random: no re-run replays its samples, so its share of
// the response stays unexplained. Where the channel's residual is described (unexplained.h), the
// noise is judged again on what the description leaves: a ripple's steps are not noise.
//
// Displacement sensor scale. A sensor reading s x the truth shows on both channels: the actuator's
// fitted gain is s g0 (the declared gain g0) and the specimen's fitted stiffness k0 / s, so that
// the force per unit command, gain x stiffness, is as declared. When a gain error is named and
// (fitted gain / g0) x fitted stiffness is within kScaleMatch of the declared stiffness k0, one
// effect explains both: "scale" s = fitted gain / g0 on "displacement sensor N" takes the place
// of "gain error" and "stiffness change". Only for a specimen whose force is linear in the
// displacement (stiffness, damping, inertia, offset): a hysteretic fit scales otherwise. A load
// cell's scale reads as a stiffness change on a linear specimen (no record tells the two apart);
// that finding says so.
//
// Displacement sensor offset. The specimen's force is fitted against the displacement read, so a
// sensor offset drift o_d + d_d s (m) shows on the force channel as -k (o_d + d_d s) (k the
// fitted stiffness term, the force's term in the displacement itself; a hysteresis moves on the
// displacement's increments only): the load cell's own offset drift is the force channel's less
// that. When both channels fitted one and the load cell's own offset and drift are each below
// kOwnOffsetShare of the force's std, the load cell's is not named.
//
// The rig's models (rig_models): what the re-run and the written study hold for one actuator path:
// where the record contradicted the declared actuator or its displacement sensor (an undeclared
// effect other than noise), the fitted actuator with its gain divided by s, else the declared
// stages stay (a fitted model of a declared tracking loop is no better than the loop); where the
// specimen is re-run (the force channel contradicted the declared specimen), the fitted specimen
// with the load cell's own offset drift only, its stiffness, damping and mass times s and its
// friction's smoothing velocity over s (tanh(v_read / v_s) = tanh(v / (v_s / s))); the sensor's
// scale itself goes into a sensor_drift stage. An effect the re-run rejected
// (ActuatorPath::rejected) is taken back out of either model (without_named), a rejected scale
// reads the sensor true.

#include <optional>
#include <span>
#include <string>

#include "identify/run/actuator_path.h"

namespace rths::identify {

inline constexpr double kNoiseShare = 0.01;         // of the signal's std
inline constexpr double kNoiseAboveDeclared = 1.2;  // x the declared noise
inline constexpr double kScaleMatch = 0.01;         // relative, of the declared stiffness
inline constexpr double kOwnOffsetShare = 0.02;     // of the force's std

// The part of the loop an effect of `channel` is on: "displacement sensor N" / "load cell N" for
// a sensor's effects (offset_drift, noise, scale, and on the force channel its delay: the load
// cell's channel late), else "actuator N" / "specimen N".
std::string part_of(const std::string& effect, Channel channel, int actuator);

// The noise each channel's noise floor shows and the displacement sensor's scale, named on `path`
// as above. Call after the specimen was judged (ActuatorPath::fitted_stiffness).
void judge_sensors(ActuatorPath& path);

// sigma (m or N) of the white part of a residual: the median of its squared steps, as above.
double white_noise(std::span<const double> residual);

// Whether a noise of sigma (m or N) on `channel` is named: above kNoiseShare of the signal's std
// and kNoiseAboveDeclared x the declared `declared`.
bool noise_named(const Identification& id, Channel channel, double sigma, double declared);

// Whether the fitted specimen's force is linear in the displacement and its rates (stiffness,
// damping, inertia, offset, delay): what a sensor's scale multiplies as a whole.
bool linear_specimen(const Identification& id);

// The std of `channel`'s target (m or N): what a noise is compared with.
double noise_spread(const Identification& id, Channel channel);

// The statistical half-width of a noise estimate sigma from the channel's samples.
double noise_std_error(const ActuatorPath& path, Channel channel, double sigma);

// `model` of `channel` on `path` with one named effect taken back out: "gain error", "delay
// change" and "stiffness change" set back to the declared value, any other effect removed
// (parameters.h without_effect).
ChannelModel without_named(const ChannelModel& model, const ActuatorPath& path,
                           const std::string& effect, const SignalScales& scales);

struct RigModels {
  std::optional<ChannelModel> actuator;  // absent: the declared actuator stays
  std::optional<ChannelModel> specimen;  // absent: the declared specimen stays
  double displacement_scale = 1.0;
  // The specimen's force effects the declared stages hold where they stay (`actuator` absent):
  // a declared tracking loop's specimen inertia and damping and its load cell's delay
  // (study_config.h add_force_stages `held`), so that the re-run does not hold them twice.
  std::vector<Effect> held_by_declared;
};
// @pre the path's measured channel was identified (throws std::invalid_argument otherwise).
RigModels rig_models(const ActuatorPath& path);

}  // namespace rths::identify
