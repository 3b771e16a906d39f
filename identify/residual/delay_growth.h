#pragma once
// A channel's lag that grows in time (a time base that runs slow or fast against the loop's),
// read from what a model with a constant lag leaves.
//
// Input: samples t_j (s), a residual r_j = y_j - p_j and the model's prediction p_j (the
// channel's unit) at a step dt (s), the model holding the channel's mean lag d (s).
// A reading late by tau(t) reads y(t) = F(t - tau(t)) ~ F(t) - tau(t) F'(t); the model reads
// p ~ F - d F', so r ~ -(tau(t) - d) p'(t). With tau(t) = d + e + g (t - t_mid) (e: what the
// mean lag misses, g: its growth, s/s):
//   r_j ~ -e p'_j - g p'_j (t_j - t_mid), least squares over every sample (p' by central
//   differences, the means of r and of the regressors removed).
// Output: the growth g (s per s of the record; 1e-4 is a time base 100 ppm slow), its standard
// error (from the fit's residual variance, white), the mean lag's miss e (s) and the share of r's
// variance the two terms explain. Reported only when g stands kGrowthSigmas standard errors from
// 0 and the terms explain kMinGrowthExplained of r.

#include <optional>
#include <span>

namespace rths::identify {

inline constexpr double kGrowthSigmas = 4.0;
inline constexpr double kMinGrowthExplained = 0.1;  // of the residual's variance

struct DelayGrowth {
  double growth = 0.0, growth_error = 0.0;  // s/s
  double mean_miss = 0.0;                   // s
  double explained = 0.0;                   // of the residual's variance
};

// @pre residual, prediction and time of the same size, dt > 0.
std::optional<DelayGrowth> delay_growth(std::span<const double> time,
                                        std::span<const double> residual,
                                        std::span<const double> prediction, double dt);

}  // namespace rths::identify
