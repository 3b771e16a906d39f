#pragma once
// Evidence that a residual hides a missing effect: what it correlates with, where its energy is.
//
//   amplitude_spectrum   one-sided amplitude of x (units of x) after removing the mean and a Hann
//                        window (amplitude-corrected), by FFTW r2c; frequency in Hz.
//   correlation          Pearson correlation of two equal-length series (0 when one is constant).
//   cross_correlation    normalised cross-correlation c(l) = sum a_i b_{i+l} / (|a| |b|) over lags
//                        |l dt| <= max_lag (mean removed, FFT-based), its largest |c| and that lag
//                        (s, positive when b lags a), refined by a parabola through the peak.
//   residual_evidence    for a channel's residual r = target - prediction: correlation of r with
//                        the input, the input's velocity, sign(velocity), the input cubed and the
//                        acceleration; the cross-correlation input -> residual; the residual
//                        spectrum's dominant frequency and the share of its power below 1 Hz.
//   noise_floor          the sensor noise of a target, relative to its spread: sigma / std(target).
//                        The signal band is where 99.5 % of the input's power lies (below f_s);
//                        above 1.5 f_s the target has (ideally) only noise, whose power there,
//                        spread as a flat density over the whole band 0..Nyquist, is sigma^2:
//                        sigma^2 = P(f > 1.5 f_s) (f_N / (f_N - 1.5 f_s)). Harmonics a nonlinear
//                        specimen puts above the band count as noise (an over-estimate); noise
//                        that the DAQ filters towards Nyquist is under-estimated.

#include <span>
#include <vector>

#include "identify/model.h"

namespace rths::identify {

struct Spectrum {
  std::vector<double> frequency;  // Hz
  std::vector<double> amplitude;
};
Spectrum amplitude_spectrum(std::span<const double> x, double dt);

double correlation(std::span<const double> a, std::span<const double> b);

struct CrossCorrelation {
  double lag = 0.0;   // s
  double peak = 0.0;  // signed normalised correlation at the lag
};
CrossCorrelation cross_correlation(std::span<const double> a, std::span<const double> b, double dt,
                                   double max_lag);

struct Evidence {
  double corr_input = 0.0, corr_velocity = 0.0, corr_velocity_sign = 0.0, corr_input_cubed = 0.0;
  double corr_acceleration = 0.0;
  CrossCorrelation input_to_residual;
  double dominant_frequency = 0.0;   // Hz
  double low_frequency_share = 0.0;  // power below 1 Hz / total
  double residual_rms = 0.0;
};
double noise_floor(std::span<const double> input, std::span<const double> target, double dt);

Evidence residual_evidence(const ChannelSignals& signals, std::span<const double> prediction);

}  // namespace rths::identify
