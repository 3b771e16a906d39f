#pragma once
// Error measures between a reference history and a compared one (same length, same step).
//
//   paper_eq2      sqrt(sum_i e_i^2) / N / median|u_ref|   -- the source paper's Eq. 2 exactly
//                  as printed. Dividing the root-sum by N makes it shrink like 1/sqrt(N): it
//                  depends on the number of steps (dt and duration), not only on the error.
//   nrmse          sqrt(mean e^2) / median|u_ref|          -- the N-independent alternative.
//   peak_error     max |e|
//   relative_peak_error_pct  E_peak = 100 max|e| / max|u_ref|       (%)
//   relative_rms_error_pct   E_rms  = 100 sqrt(sum e^2 / sum u_ref^2) (%)
//                  The errors a lab reads: against the reference's own peak and RMS, so a miss of
//                  a tenth of the peak reads 10 %, whatever the record's quiet tail. A zero
//                  reference gives inf (or NaN for zero error).
//   J1 (s)         delay of `measured` behind `target` by cross-correlation peak, with parabolic
//                  sub-sample refinement (RTHS benchmark, Silva, Dyke et al. 2020).
//   J2 (%)         100 sqrt(sum (x_m - x_t)^2 / sum x_t^2)  normalised RMS tracking error.
//   J3 (%)         100 max|x_m - x_t| / max|x_t|           peak tracking error.
//   median         the textbook median: the middle value, or the mean of the two middle values.
//   mean           sum_i x_i / N                            (units of x)
//   standard_deviation         sqrt(sum_i (x_i - mean)^2 / N)        population, units of x
//   sample_standard_deviation  sqrt(sum_i (x_i - mean)^2 / (N - 1))  from a sample, units of x;
//                  needs N >= 2.
//   grew_past_reference  divergence judged from the response: |u| of a case beyond
//                  kDivergenceGrowth times the peak of its lag-free reference (or not finite).
// All throw std::invalid_argument on empty or different-length inputs.

#include <span>
#include <vector>

namespace rths::core {

double paper_eq2(std::span<const double> reference, std::span<const double> compared);
double nrmse(std::span<const double> reference, std::span<const double> compared);
double peak_error(std::span<const double> reference, std::span<const double> compared);
double relative_peak_error_pct(std::span<const double> reference, std::span<const double> compared);
double relative_rms_error_pct(std::span<const double> reference, std::span<const double> compared);
double peak_abs(std::span<const double> x);
double median_abs(std::span<const double> x);
double median(std::vector<double> values);
double mean(std::span<const double> x);
double standard_deviation(std::span<const double> x);
double sample_standard_deviation(std::span<const double> x);

// A lagged case whose peak response is more than this many times its lag-free reference's has
// diverged. A stable case near its critical delay can amplify a resonant response a few times
// (5 % -> 1 % damping at resonance: 5x); an order of magnitude is growth no stable test shows.
inline constexpr double kDivergenceGrowth = 10.0;
bool grew_past_reference(double reference_peak, double case_peak);

double j1_delay(std::span<const double> target, std::span<const double> measured, double dt,
                double max_lag);
double j2_tracking(std::span<const double> target, std::span<const double> measured);
double j3_peak_tracking(std::span<const double> target, std::span<const double> measured);

}  // namespace rths::core
