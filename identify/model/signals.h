#pragma once
// A channel's signals prepared for fitting: input, its smoothed derivatives, the target, the slow-
// drift basis over the record, and their typical magnitudes (SI units).

#include <cstddef>
#include <span>
#include <vector>

#include "identify/model/data.h"
#include "identify/model/effects.h"

namespace rths::identify {

// D(s; c) above, for s in [-1/2, 1/2].
double drift_profile(std::span<const double> coefficients, double s);

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
  double target_peak = 1.0;  // max |target|
};
SignalScales signal_scales(const ChannelSignals& signals);

}  // namespace rths::identify
