#pragma once
// Where, when and at what frequencies a residual lies, and what it follows: the numerics the
// never-silent floor (identify/run/residual_floor.h) reads a channel's residual with.
//
// Input: samples t_j (s) of a residual r_j (any unit), at a step dt (s).
//   windows   the record cut into kFloorWindows equal windows, each with its share of the
//             residual's power (sum r^2); a window holds it when its share is at least
//             kWindowOverUniform / kFloorWindows; adjacent ones merge; at most kMaxWindows, the
//             largest first. None: spread over the record.
//   band      r's amplitude spectrum (spectra.h, mean removed, Hann): its peak frequency and the
//             band holding the middle 80 % of its power (10th to 90th percentile), Hz; DC left out.
//   above     r's RMS above a cutoff (Hz): sqrt(mean r^2 x the spectrum's power share there).
//   relation  the share of r's variance a function of a signal x explains with no form presumed:
//             r's mean in kRelationBins equal-count bins of x (the correlation ratio
//             1 - sum (r - bin mean)^2 / sum (r - mean)^2). A least-squares fit leaves r
//             uncorrelated with whatever its model holds linearly (a gain on the command), so a
//             straight correlation misses a dependence a map finds (the cubic part of a stroke).

#include <cstddef>
#include <span>
#include <vector>

namespace rths::identify {

inline constexpr std::size_t kFloorWindows = 20;
inline constexpr double kWindowOverUniform = 2.0;
inline constexpr std::size_t kMaxWindows = 3;
inline constexpr std::size_t kRelationBins = 16;

struct ResidualWindow {
  double start = 0.0, end = 0.0;  // s
  double share = 0.0;             // of the residual's power
};

struct ResidualBand {
  double peak_hz = 0.0, low_hz = 0.0, high_hz = 0.0;  // all 0 when r has no power
};

// @pre time and residual of the same size, at least kFloorWindows samples.
std::vector<ResidualWindow> residual_windows(std::span<const double> time,
                                             std::span<const double> residual);
ResidualBand residual_band(std::span<const double> r, double dt);
// 0 without a cutoff (cutoff <= 0) or with fewer than 16 samples.
double rms_above(std::span<const double> r, double dt, double cutoff);
// 0 when x and r differ in size or hold fewer than 2 kRelationBins samples.
double correlation_ratio(std::span<const double> x, std::span<const double> r);

}  // namespace rths::identify
