#pragma once
// Parametric models of the two measured channels and the library of effects they may contain.
//
// Channel `measured` (the actuator): input command u_c(t) (m) -> measured displacement (m):
//   x(t)  = u_c(t - tau(t))                 tau(t) = max(0, delay + D(s(t); delay_c))
//   (interpolated) x    -> first-order lag    T dy/dt = x - y                  (exact for a held
//   sample)
//        -> second-order lag   y'' + 2 zeta wn y' + wn^2 y = wn^2 x   (Tustin)
//        -> backlash / dead band of total width b (play operator)
//        -> velocity saturation |dy/dt| <= v_max
//   u_m  = gain (1 + D(s(t); gain_c)) * y + offset + drift * s(t)
// Channel `force` (the specimen): input measured displacement d, velocity v, acceleration a
// (shifted by the force delay when present) -> force (N):
//   F = (k + D(s(t); k_c)) d + k3 d^3 + c v + F_c tanh(v / v_c) + m a + F_bw z + p
//       + offset + drift s
//   elasto-plastic element p (the bilinear specimen with the spring k as post-yield stiffness):
//   p_j = clamp(p_{j-1} + k_p (d_j - d_{j-1}), -F_y, F_y).
//   Bouc–Wen z (dimensionless, |z| <= 1), n = 1, beta = gamma = 1/2 over the drift increment:
//   dz/dd = (1 - |z| (sgn(dd z) + 1) / 2) / d_y, integrated exactly per step.
// s(t) = (t - t_mid) / duration is the normalised time, in [-1/2, 1/2].
// Slow drifts (time-varying delay, gain, stiffness) are zero-mean cosine series over the record:
//   D(s; c) = sum_{k=1..K} c_k cos(pi k (s + 1/2))
// (K = kDriftTerms), smooth, orthogonal over the record and free of a constant part, so the
// constant delay / gain / stiffness keeps its meaning as the record's mean.
// Bounds are physical: stiffness, damping, mass, friction and hysteretic forces >= 0; delays >= 0
// and shorter than half the record; time constants between a fifth of a sample step and 1 s and
// natural frequencies below Nyquist (finite bandwidth).
// Every effect is the parametric addition of its terms to the model; an effect absent from the
// model contributes nothing. All parameters are in SI units.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "identify/data.h"

namespace rths::identify {

enum class Channel { kMeasured, kForce };
std::string channel_name(Channel channel);

enum class Effect {
  // either channel
  kDelay,        // constant delay (actuator lag, or force lagging displacement)
  kOffsetDrift,  // constant offset + linear drift
  // actuator (channel measured)
  kFirstOrder,
  kSecondOrder,
  kBacklash,
  kVelocitySaturation,
  kTimeVaryingDelay,
  kTimeVaryingGain,
  // specimen (channel force)
  kStiffness,
  kDamping,
  kCoulomb,
  kBoucWen,
  kCubicStiffness,
  kTimeVaryingStiffness,
  kInertia,
  kElastoPlastic,
};

// Number of cosine terms of every slow drift D(s; c).
inline constexpr std::size_t kDriftTerms = 8;
// D(s; c) above, for s in [-1/2, 1/2].
double drift_profile(std::span<const double> coefficients, double s);

std::string effect_name(Effect effect);
// Inverse of effect_name ("delay", "first_order", ...). Throws std::invalid_argument.
Effect parse_effect(const std::string& name);
bool effect_applies(Effect effect, Channel channel);
// Every effect of the library that applies to the channel, in a fixed order.
std::vector<Effect> effect_library(Channel channel);

// The prepared signals of one channel: input, its derivatives and the target, at step dt.
struct ChannelSignals {
  Channel channel = Channel::kMeasured;
  double dt = 0.0;
  std::vector<double> time, input, velocity, acceleration, target;
  // What the model runs on (predict): the force channel's specimen model is driven by
  // model_input, velocity and acceleration; empty = input itself (the actuator's clean command).
  std::vector<double> model_input;
  double input_cutoff = 0.0;  // Hz, the low-pass that made model_input from input; 0 = none
  // The slow drifts' basis at every sample, row-major n x kDriftTerms: cos(pi k (s_j + 1/2)),
  // k = 1..kDriftTerms, s_j the normalised time of sample j (drift_basis()). make_signals fills it
  // so that predict, run thousands of times per fit, evaluates no cosine; empty = computed per
  // call.
  std::vector<double> drift_basis;
  // Unique to one make_signals call (copies share it; 0 = none): lets predict reuse, within a
  // thread, the friction and hysteresis sequences of the last call on the same signals when their
  // parameters are unchanged (a Jacobian column of another parameter), with the same values.
  std::uint64_t id = 0;
  std::size_t size() const { return time.size(); }
};

// The rows of ChannelSignals::drift_basis for `time` (s, increasing): s_j = (t_j - t_mid) /
// duration with t_mid the record's centre and duration = max(t_last - t_first, dt).
std::vector<double> drift_basis(std::span<const double> time, double dt);

// The specimen model's input is low-passed at f_c = max(kSpecimenInputCutoffFactor x the input's
// signal band, the input's noise edge) (evidence.h signal_band, noise_edge): far enough above the
// band that the band passes unchanged (the zero-phase magnitude 1 / (1 + (f / f_c)^8) is 0.9993
// at the band's edge), and not below where the displacement still rises above its noise (a
// broadband record's tail, which velocity and acceleration weigh up); above f_c the displacement
// sensor's noise, which the model would turn into force through every hysteretic and friction
// switch, no longer reaches the model.
inline constexpr double kSpecimenInputCutoffFactor = 2.5;

// `measured`: input = command, the model runs on it unfiltered. `force`: input = measured
// displacement; model_input = input low-passed, zero phase, at f_c above (zero_phase_lowpass;
// none when f_c >= 0.8 x Nyquist or the noise edge cannot be estimated). Velocity and
// acceleration are central differences of the model's input after a zero-phase moving average
// over `smooth_window` seconds (keeps differentiated noise out of the force model). `input` itself
// stays as measured (plots, evidence, the noise floor).
ChannelSignals make_signals(const MeasuredData& data, Channel channel,
                            double smooth_window = 0.005);

// Zero-phase 4th-order Butterworth low-pass at `cutoff` (Hz), run forward and backward
// (magnitude 1 / (1 + (f / cutoff)^8), no phase), each pass started at rest at its first value.
// Two Tustin biquads pre-warped at the cut-off, quality factors 1 / (2 cos(pi/8)) and
// 1 / (2 cos(3 pi/8)). @pre 0 < cutoff < 0.5 / dt; throws std::invalid_argument otherwise.
std::vector<double> zero_phase_lowpass(std::span<const double> x, double dt, double cutoff);

// Typical magnitudes of the signals: used to scale parameters and to seed guesses.
struct SignalScales {
  double input = 1.0, velocity = 1.0, acceleration = 1.0, target = 1.0, duration = 1.0, dt = 1.0;
};
SignalScales signal_scales(const ChannelSignals& signals);

struct ParamSpec {
  std::string name, unit;
  double scale = 1.0;  // typical magnitude, so that value / scale is O(1) for the fit
  double lower = -1e300, upper = 1e300;
  std::vector<double> guesses;  // starting values tried when the effect is added
  // What a value below `lower` would mean physically ("a negative stiffness"); empty when the
  // lower bound is numerical only.
  std::string below_means;
  // Offsets, drifts and drift coefficients belong to one record: re-estimated, not carried over,
  // when a model is validated on another record.
  bool record_specific = false;
  // Held at its value by every fit (a declared model's `fixed`, see ParamDeclaration).
  bool fixed = false;
};

// What a declared model (proto/identify.proto, identify/declared_model.h) says of one parameter,
// keyed by its name (parameter names are unique within a channel):
//   initial  replaces the library's starting guesses;
//   lower / upper narrow the physical bounds (max(physical, declared), min(...)), never widen them;
//   fixed    holds the parameter at its value in every fit.
// A declaration whose name is not in the model has no effect (it applies once the effect is added).
struct ParamDeclaration {
  std::string name;
  std::optional<double> initial, lower, upper;
  bool fixed = false;
};

// `specs` with the declarations of the same names applied. When a declared lower bound is above
// the physical one, the bound hit is about the declared bound, so below_means is cleared.
std::vector<ParamSpec> declared_specs(std::vector<ParamSpec> specs,
                                      const std::vector<ParamDeclaration>& declarations);

// The parameters an effect adds (in order). Base parameters of a channel: `gain` for measured,
// none for force.
std::vector<ParamSpec> effect_params(Effect effect, Channel channel, const SignalScales& scales);
std::vector<ParamSpec> base_params(Channel channel, const SignalScales& scales);

struct ChannelModel {
  Channel channel = Channel::kMeasured;
  std::vector<Effect> effects;  // in the order they were added
  std::vector<double> params;   // base params, then each effect's params in `effects` order
  // Parameters held at their value by the fit (same indexing as params; missing = free).
  std::vector<bool> fixed;
  // The declared model's word on parameters (by name); specs() applies them, so every fit,
  // k-fold and validation of this model and of the models grown from it respects them.
  std::vector<ParamDeclaration> declarations;

  bool has(Effect effect) const;
  bool is_fixed(std::size_t index) const { return index < fixed.size() && fixed[index]; }
  // Index of the named parameter of `effect` (or of the base when effect is empty) in params.
  std::optional<std::size_t> index_of(std::optional<Effect> effect, const std::string& name,
                                      const SignalScales& scales) const;
  // The effect that owns parameter `index` (empty for a base parameter).
  std::optional<Effect> effect_of(std::size_t index, const SignalScales& scales) const;
  // Library specs of base and effects, with `declarations` applied; a spec is `fixed` when its
  // declaration or this model's `fixed` holds it: the one place a fit asks.
  std::vector<ParamSpec> specs(const SignalScales& scales) const;
  // The value of the named parameter of `effect` (or of the base when effect is empty).
  std::optional<double> param(std::optional<Effect> effect, const std::string& name,
                              const SignalScales& scales) const;
  std::string describe(const SignalScales& scales) const;
};

// The declared model with neutral parameter values (gain 1, delay 0, stiffness 0).
ChannelModel declared_model(Channel channel, const std::vector<Effect>& effects,
                            const SignalScales& scales);
// `model` with `effect` appended, its params set to `guess` (one per ParamSpec).
ChannelModel with_effect(const ChannelModel& model, Effect effect, std::span<const double> guess);
// `model` without `effect` and its params. Throws std::invalid_argument when it is absent.
ChannelModel without_effect(const ChannelModel& model, Effect effect, const SignalScales& scales);

// Model output over the whole record (the state runs from sample 0, at rest at the first input).
void predict(const ChannelModel& model, std::span<const double> params,
             const ChannelSignals& signals, std::vector<double>& out);
std::vector<double> predict(const ChannelModel& model, const ChannelSignals& signals);

// RMS(target - prediction) / std(target) over the given samples.
double normalised_error(std::span<const double> target, std::span<const double> prediction,
                        std::span<const std::size_t> samples);

}  // namespace rths::identify
