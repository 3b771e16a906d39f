#pragma once
// Spectra and correlations of measured signals, the tools identification reads residuals with.
//
//   amplitude_spectrum   one-sided amplitude of x (units of x) after removing the mean and a Hann
//                        window (amplitude-corrected), by FFTW r2c; frequency in Hz.
//   correlation          Pearson correlation of two equal-length series (0 when one is constant).
//   cross_correlation    normalised cross-correlation c(l) = sum a_i b_{i+l} / (|a| |b|) over lags
//                        |l dt| <= max_lag (mean removed, FFT-based), its largest |c| and that lag
//                        (s, positive when b lags a), refined by a parabola through the peak.
//   signal_band          f_s (Hz): the frequency below which 99.5 % of x's power lies (mean
//                        removed; 0 for fewer than 16 samples or no power).
//   transfer_estimate    H1(f) = S_xy(f) / S_xx(f) of output y against input x by Welch averaging:
//                        segments of `segment` samples with 50 % overlap, each with its mean
//                        removed and a Hann window, their FFTW r2c transforms' cross and auto
//                        spectra summed; coherence gamma^2 = |S_xy|^2 / (S_xx S_yy) in [0, 1].
//                        Bins 1 .. segment/2 (DC left out), f_k = k / (segment dt) Hz; magnitude
//                        in units of y per unit of x; phase (rad) unwrapped from the lowest bin.
//   noise_edge           where x's spectrum has sunk to its noise (Hz): the first frequency above
//                        the signal band where x's Welch power density (5-bin average) is at most
//                        10 x its noise density, the median density above 1.5 x the band (which
//                        holds only noise, as for noise_floor). Nyquist when the spectrum never
//                        sinks that far; 0 when it cannot be estimated (fewer than 512 samples, no
//                        power, or no band above 1.5 x the signal band).
//   noise_floor          the sensor noise of a target, relative to its spread: sigma / std(target).
//                        The signal band is where 99.5 % of the input's power lies (below f_s);
//                        above 1.5 f_s the target has (ideally) only noise, whose power there,
//                        spread as a flat density over the whole band 0..Nyquist, is sigma^2:
//                        sigma^2 = P(f > 1.5 f_s) (f_N / (f_N - 1.5 f_s)). Harmonics a nonlinear
//                        specimen puts above the band count as noise (an over-estimate); noise
//                        that the DAQ filters towards Nyquist is under-estimated.

#include <cstddef>
#include <span>
#include <vector>

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

struct TransferEstimate {
  std::vector<double> frequency, magnitude, phase, coherence;  // Hz, y/x, rad, -
  std::size_t segments = 0;
};
// @pre x and y of equal length >= segment >= 8; throws std::invalid_argument otherwise.
TransferEstimate transfer_estimate(std::span<const double> x, std::span<const double> y, double dt,
                                   std::size_t segment);

double signal_band(std::span<const double> x, double dt);
double noise_edge(std::span<const double> x, double dt);
double noise_floor(std::span<const double> input, std::span<const double> target, double dt);

}  // namespace rths::identify
