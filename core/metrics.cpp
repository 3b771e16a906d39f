#include "core/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rths::core {
namespace {

void require_pair(std::span<const double> reference, std::span<const double> compared,
                  const char* metric) {
  if (reference.empty() || compared.empty()) {
    throw std::invalid_argument(std::string(metric) + ": empty input");
  }
  if (reference.size() != compared.size()) {
    throw std::invalid_argument(std::string(metric) + ": inputs differ in length (" +
                                std::to_string(reference.size()) + " vs " +
                                std::to_string(compared.size()) + ")");
  }
}

double sum_squared_error(std::span<const double> a, std::span<const double> b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double e = b[i] - a[i];
    sum += e * e;
  }
  return sum;
}

// sum_i (x_i - mean)^2 (units of x squared); x is not empty.
double squared_deviation_sum(std::span<const double> x) {
  const double centre = mean(x);
  double sum = 0.0;
  for (double value : x) sum += (value - centre) * (value - centre);
  return sum;
}

}  // namespace

// A diverged run must show as NaN, not as whatever std::max happens to keep.
double peak_abs(std::span<const double> x) {
  double peak = 0.0;
  for (double value : x) {
    if (std::isnan(value)) return std::numeric_limits<double>::quiet_NaN();
    peak = std::max(peak, std::abs(value));
  }
  return peak;
}

double median(std::vector<double> values) {
  if (values.empty()) throw std::invalid_argument("median: empty input");
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle),
                   values.end());
  const double upper = values[middle];
  if (values.size() % 2 == 1) return upper;
  // Even length: the mean of the two middle values; the lower one is the largest below `middle`.
  const double lower =
      *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle));
  return 0.5 * (lower + upper);
}

double mean(std::span<const double> x) {
  if (x.empty()) throw std::invalid_argument("mean: empty input");
  double sum = 0.0;
  for (double value : x) sum += value;
  return sum / static_cast<double>(x.size());
}

double standard_deviation(std::span<const double> x) {
  if (x.empty()) throw std::invalid_argument("standard_deviation: empty input");
  return std::sqrt(squared_deviation_sum(x) / static_cast<double>(x.size()));
}

double sample_standard_deviation(std::span<const double> x) {
  if (x.size() < 2) {
    throw std::invalid_argument("sample_standard_deviation: needs 2 values or more, got " +
                                std::to_string(x.size()));
  }
  return std::sqrt(squared_deviation_sum(x) / static_cast<double>(x.size() - 1));
}

double median_abs(std::span<const double> x) {
  if (x.empty()) throw std::invalid_argument("median_abs: empty input");
  std::vector<double> magnitudes(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) magnitudes[i] = std::abs(x[i]);
  return median(std::move(magnitudes));
}

bool grew_past_reference(double reference_peak, double case_peak) {
  return !std::isfinite(case_peak) || case_peak > kDivergenceGrowth * reference_peak;
}

// Literal Eq. 2: the 1/N outside the root is the paper's, so the value scales as 1/sqrt(N).
// A zero median gives inf (or NaN for zero error), which a report must show, not hide.
double paper_eq2(std::span<const double> reference, std::span<const double> compared) {
  require_pair(reference, compared, "paper_eq2");
  const double n = static_cast<double>(reference.size());
  return std::sqrt(sum_squared_error(reference, compared)) / n / median_abs(reference);
}

double nrmse(std::span<const double> reference, std::span<const double> compared) {
  require_pair(reference, compared, "nrmse");
  const double n = static_cast<double>(reference.size());
  return std::sqrt(sum_squared_error(reference, compared) / n) / median_abs(reference);
}

double peak_error(std::span<const double> reference, std::span<const double> compared) {
  require_pair(reference, compared, "peak_error");
  double peak = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const double e = std::abs(compared[i] - reference[i]);
    if (std::isnan(e)) return std::numeric_limits<double>::quiet_NaN();
    peak = std::max(peak, e);
  }
  return peak;
}

double relative_peak_error_pct(std::span<const double> reference,
                               std::span<const double> compared) {
  require_pair(reference, compared, "relative_peak_error_pct");
  return 100.0 * peak_error(reference, compared) / peak_abs(reference);
}

double relative_rms_error_pct(std::span<const double> reference, std::span<const double> compared) {
  require_pair(reference, compared, "relative_rms_error_pct");
  double reference_energy = 0.0;
  for (double x : reference) reference_energy += x * x;
  return 100.0 * std::sqrt(sum_squared_error(reference, compared) / reference_energy);
}

// r(L) = sum t_i m_{i+L} / sqrt(sum t_i^2 sum m_{i+L}^2) over the overlap of the two records;
// a positive L means `measured` lags. Normalising by the energies of the same overlap cancels,
// to first order, the edge terms a finite record leaves (a window that no longer covers whole
// periods); a plain or overlap-averaged sum leaves them in and biases a slow sine's peak by
// whole samples.
double j1_delay(std::span<const double> target, std::span<const double> measured, double dt,
                double max_lag) {
  require_pair(target, measured, "j1_delay");
  if (!(dt > 0.0)) throw std::invalid_argument("j1_delay: dt must be > 0");
  if (!(max_lag >= 0.0)) throw std::invalid_argument("j1_delay: max_lag must be >= 0");
  const long n = static_cast<long>(target.size());
  const long max_steps = std::min<long>(n - 1, static_cast<long>(std::ceil(max_lag / dt - 1e-9)));
  const auto correlation = [&](long lag) {
    const long begin = std::max<long>(0, -lag), end = std::min<long>(n, n - lag);
    double cross = 0.0, target_energy = 0.0, measured_energy = 0.0;
    for (long i = begin; i < end; ++i) {
      const double a = target[static_cast<std::size_t>(i)];
      const double b = measured[static_cast<std::size_t>(i + lag)];
      cross += a * b;
      target_energy += a * a;
      measured_energy += b * b;
    }
    const double norm = std::sqrt(target_energy * measured_energy);
    return norm > 0.0 ? cross / norm : 0.0;
  };
  long best = 0;
  double best_value = -std::numeric_limits<double>::infinity();
  for (long lag = -max_steps; lag <= max_steps; ++lag) {
    const double value = correlation(lag);
    if (value > best_value) {
      best_value = value;
      best = lag;
    }
  }
  double refinement = 0.0;
  if (best > -max_steps && best < max_steps) {
    const double left = correlation(best - 1), right = correlation(best + 1);
    const double curvature = left - 2.0 * best_value + right;
    if (curvature < 0.0) refinement = 0.5 * (left - right) / curvature;
  }
  return (static_cast<double>(best) + refinement) * dt;
}

double j2_tracking(std::span<const double> target, std::span<const double> measured) {
  require_pair(target, measured, "j2_tracking");
  return relative_rms_error_pct(target, measured);
}

double j3_peak_tracking(std::span<const double> target, std::span<const double> measured) {
  require_pair(target, measured, "j3_peak_tracking");
  return relative_peak_error_pct(target, measured);
}

}  // namespace rths::core
