#pragma once
// A residual described without presuming an effect: the pure numerics of what an identified
// model leaves (identify/run/unexplained.h applies them to a run's channels).
//
// Input: samples t_j (s), a residual r_j = y_j - p_j (the channel's unit) and the model's
// prediction p_j (the same unit), at a step dt (s).
//   split      the record cut into kDescriptionWindows contiguous windows: even ones train every
//              description, odd ones judge it (held-out). explained(d) = 1 - var_h(r - d) /
//              var_h(r) over the held-out samples (variances about their means: a constant is an
//              offset, the library's offset_drift, not a signature).
//   amplitude  a static map M(p) of the residual against the model's output p, the channel's
//   direction  input as the model carries it to the output, with no form: kMapBins bins at
//              quantiles of p on the train samples, each the mean residual at the mean p of its
//              bin, linear between bins and along the end segments beyond them. Its odd part
//              (M(p) - M(-p)) / 2 less its line through 0 (a gain, the model's) is a reading that
//              changes with the input's amplitude ("amplitude": ratio_change_pct = 100 (M_odd(p_98)
//              / p_98 - M_odd(p_50) / p_50), the measured / model ratio from the median to the
//              98th percentile of |p|); its even part, less its mean, a reading that depends on the
//              input's sign ("direction": asymmetry_pct = 100 (g+ - g-), g+- = sum r p / sum p^2
//              over the train samples with p of that sign: how much more the positive side reads
//              than the negative, relative to the model). The kind is the larger of the two
//              powers over the held-out samples. A second map per sign of dp/dt (loading,
//              unloading) is "direction" too when it explains kMinExplained more than the one
//              map: hysteresis_width = the RMS of M+(p) - M-(p) (unit). A third map, over p's
//              rate v = dp/dt (central differences), is kept instead where it explains
//              kMinExplained and more than the others: read the same way, its even part is
//              "direction" (the direction of motion: lead_difference = g+ - g- over v, s: how much
//              more the measured leads the model rising than falling, an actuator slower one way),
//              its odd part less its line "amplitude" (the rate's amplitude: lead_change = M_odd(v)
//              / v from the median to the 98th percentile of |v|, s: a flow or a damping that
//              grows unlike the model's). A residual of the rate is no function of p (a lag's
//              residual is a quarter period from it), so the maps over p miss it.
//   time_varying the gain of the residual on the model, rho_w = sum r p / sum p^2, in each window:
//              the measured / model ratio tracked over the record, described as linear between
//              the train windows' values (no form); reported when that explains kMinExplained
//              and the line through every window's rho has a slope at least kTrendSigmas standard
//              errors from 0: change_pct = 100 x the slope x the record's duration (start to end).
//              The map and the trend are tried in both orders (a residual of the amplitude on a
//              record whose amplitude changes over time shows in both); the order that leaves the
//              smaller held-out variance is kept.
//   periodic   on what they leave: the amplitude spectrum (Hann, FFTW: spectra.h) above
//              kMinPeriodicFrequency of its train samples; its highest peak, when at least
//              kPeakOverFloor x the median amplitude within kFloorBand Hz of it and where p's own
//              spectrum is below kInputPeakShare of its largest amplitude or, where it is not,
//              the residual's spectrum over p's stands kPeakOverFloor x above its median within
//              kFloorBand Hz (a model's error on the input follows the input's spectrum and is
//              the maps' to judge; a period of another source, a neighbour's test at a frequency
//              the motion holds too, stands out of it), is refined on a grid of a tenth of a bin
//              (the largest |sum r_j exp(-2 pi i f t_j)|) and fitted as a sinusoid a cos + b sin
//              on the train samples: frequency (Hz) and amplitude sqrt(a^2 + b^2) (the channel's
//              unit). Where the fast band holds none that explains kMinExplained, the slow band,
//              from kMinPeriodicCycles / the record's duration up to kMinPeriodicFrequency, of the
//              train samples less their line (a drift is the library's offset_drift): its highest
//              bin, taken only where every bin below it is lower (a drift's spectrum falls from
//              0 Hz, a period's rises to its frequency), standing out and not the input's as above.
//              Where neither order finds a trend, the same test on what they left against p's
//              rate v = dp/dt (rho_w = sum r v / sum v^2, s: the measured's lead on the model,
//              of_rate): a term in quadrature with p whose size moves over the record (a damper
//              whose oil warms, a lag that grows) is no ratio to p and shows only there; kept
//              only where the windows' rho follows time more closely (the sum of squares its line
//              leaves) than the windows' RMS rate (a force in v |v| on a motion that grows reads
//              as a lead that grows with the rate, not with time).
//   trend shape the windows' rho fitted as a line, a step and an exponential approach
//              (drift_shape.h): the shape, the ratio at the start and at the end of the record.
// A test counts only when it explains at least kMinExplained of the residual's held-out variance
// (on what the tests before it left).

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "identify/residual/drift_shape.h"

namespace rths::identify {

inline constexpr std::size_t kDescriptionWindows = 20;
inline constexpr std::size_t kMapBins = 16;
inline constexpr double kMinExplained = 0.3;   // of the residual's held-out variance
inline constexpr double kPeakOverFloor = 8.0;  // spectral peak / its neighbourhood's median
inline constexpr double kFloorBand = 2.0;      // Hz either side of the peak
// Hz: below it (the slow band) a period must show as one in the spectrum (slow_peak), since a
// drift piles up there too.
inline constexpr double kMinPeriodicFrequency = 0.5;
// The slowest period searched: this many cycles in the record (a rise, a fall and half of the
// next rise: a shape that comes back, which no single drift makes).
inline constexpr double kMinPeriodicCycles = 1.5;
inline constexpr double kInputPeakShare = 0.1;  // of the input's largest spectral amplitude
inline constexpr double kTrendSigmas = 4.0;

struct PeriodicSignature {
  double frequency = 0.0;  // Hz
  double amplitude = 0.0;  // the channel's unit
  double explained = 0.0;  // held-out share of the residual's variance
};
struct AmplitudeSignature {
  double explained = 0.0;
  double ratio_change_pct = 0.0;  // measured / model, from the median to the 98th percentile
  double at_input = 0.0;          // the 98th percentile of |p| (unit), of |dp/dt| (unit/s) of_rate
  bool of_rate = false;           // a function of the rate's amplitude, not of p's
  double lead_change = 0.0;       // s, of_rate: the measured's lead on the model, median to 98th
};
struct DirectionSignature {
  double explained = 0.0;
  double asymmetry_pct = 0.0;     // positive side's measured / model less the negative side's
  double hysteresis_width = 0.0;  // unit; 0 when loading and unloading read alike
  bool of_rate = false;  // a function of the rate's sign (the direction of motion), not of p's
  // s, of_rate: the measured's lead on the model while p rises less its lead while p falls (a lag
  // 8 ms shorter rising: +0.008).
  double lead_difference = 0.0;
};
struct TrendSignature {
  double explained = 0.0;
  double change_pct = 0.0;  // of the measured / model ratio, start to end of the record
  // rho's shape over the windows (drift_shape.h): start and end are measured / model - 1, or,
  // of_rate, the measured's lead on the model (s; change_pct is then 0).
  ShapeFit shape;
  bool of_rate = false;
};

// One channel's description (describe_residual).
struct ResidualDescription {
  std::optional<PeriodicSignature> periodic;
  std::optional<AmplitudeSignature> amplitude;
  std::optional<DirectionSignature> direction;
  std::optional<TrendSignature> time_varying;
  double explained = 0.0;      // held-out, by every accepted test together
  double residual_rms = 0.0;   // unit, of r about its mean
  double heldout_rms = 0.0;    // unit, of r - described on the held-out samples
  double described_rms = 0.0;  // unit, of what the accepted tests describe, about its mean
  // Unit, at every sample: what the accepted tests describe, with the residual's mean (train)
  // when any test was accepted (what a re-run puts back).
  std::vector<double> described;
  bool any() const { return periodic || amplitude || direction || time_varying; }
  std::vector<std::string> kinds() const;
};

// @pre residual and prediction of the same size, at least 2 kDescriptionWindows kMapBins samples.
ResidualDescription describe_residual(std::span<const double> time,
                                      std::span<const double> residual,
                                      std::span<const double> prediction, double dt);

// The RMS of `residual` about its mean over the held-out windows (kDescriptionWindows, odd ones).
double heldout_rms(std::span<const double> residual);

// a - b at every sample.
std::vector<double> minus(std::span<const double> a, std::span<const double> b);

}  // namespace rths::identify
