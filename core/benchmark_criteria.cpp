#include "core/benchmark_criteria.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/metrics.h"

namespace rths::core {

double normalised_std_error(std::span<const double> reference, std::span<const double> compared) {
  if (reference.empty() || reference.size() != compared.size()) {
    throw std::invalid_argument("normalised_std_error: inputs are empty or differ in length");
  }
  const double n = static_cast<double>(reference.size());
  double mean_error = 0.0, mean_reference = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    mean_error += compared[i] - reference[i];
    mean_reference += reference[i];
  }
  mean_error /= n;
  mean_reference /= n;
  double error_square = 0.0, reference_square = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const double e = compared[i] - reference[i] - mean_error;
    const double r = reference[i] - mean_reference;
    error_square += e * e;
    reference_square += r * r;
  }
  return 100.0 * std::sqrt(error_square / reference_square);
}

BenchmarkCriteria benchmark_criteria(std::span<const double> target,
                                     std::span<const double> measured, const Mat& response,
                                     const Mat& reference, int experimental_storey, double dt,
                                     double j1_max_lag) {
  const int floors = static_cast<int>(reference.cols());
  if (response.cols() != reference.cols()) {
    throw std::invalid_argument("benchmark_criteria: the response and the reference have " +
                                std::to_string(response.cols()) + " and " + std::to_string(floors) +
                                " floors");
  }
  if (experimental_storey < 0 || experimental_storey >= floors) {
    throw std::invalid_argument("benchmark_criteria: experimental storey " +
                                std::to_string(experimental_storey + 1) + " is outside 1.." +
                                std::to_string(floors));
  }
  const std::size_t n =
      std::min({target.size(), measured.size(), static_cast<std::size_t>(response.rows()),
                static_cast<std::size_t>(reference.rows())});
  if (n < 2) throw std::invalid_argument("benchmark_criteria: fewer than two common steps");
  const auto column = [n](const Mat& m, int c) {
    std::vector<double> out(n);
    for (std::size_t i = 0; i < n; ++i) out[i] = m(static_cast<Eigen::Index>(i), c);
    return out;
  };
  std::vector<double> reference_drift = column(reference, experimental_storey);
  if (experimental_storey > 0) {
    const std::vector<double> below = column(reference, experimental_storey - 1);
    for (std::size_t i = 0; i < n; ++i) reference_drift[i] -= below[i];
  }
  const std::span<const double> t = target.first(n), m = measured.first(n);

  BenchmarkCriteria out;
  out.j.fill(std::numeric_limits<double>::quiet_NaN());
  out.j1_search = j1_max_lag;
  out.j[0] = j1_delay(t, m, dt, j1_max_lag);
  out.j[1] = normalised_std_error(t, m);
  out.j[2] = j3_peak_tracking(t, m);
  out.j[3] = normalised_std_error(reference_drift, m);
  out.j[4] = j3_peak_tracking(reference_drift, m);
  int slot = 0;
  for (int floor = 0; floor < floors && slot < 2; ++floor) {
    if (floor == experimental_storey) continue;
    const std::vector<double> ref = column(reference, floor), rths = column(response, floor);
    out.j[static_cast<std::size_t>(5 + slot)] = normalised_std_error(ref, rths);
    out.j[static_cast<std::size_t>(7 + slot)] = j3_peak_tracking(ref, rths);
    ++slot;
  }
  return out;
}

const std::array<CriterionDefinition, 9>& criterion_definitions() {
  static const std::array<CriterionDefinition, 9> definitions = {{
      {"J1", "ms", "delay of x_m behind x_t at their cross-correlation peak (tracking delay)"},
      {"J2", "%", "100 std(x_m - x_t) / std(x_t) (RMS tracking error)"},
      {"J3", "%", "100 max|x_m - x_t| / max|x_t| (peak tracking error)"},
      {"J4", "%",
       "100 std(x_m - d_ref) / std(d_ref) (RMS error of the experimental storey's drift)"},
      {"J5", "%", "100 max|x_m - d_ref| / max|d_ref| (peak error of that drift)"},
      {"J6", "%",
       "100 std(u_i - u_ref,i) / std(u_ref,i), i the first floor other than the experimental "
       "one (RMS error; the benchmark's floor 2)"},
      {"J7", "%", "as J6 for the second other floor (the benchmark's floor 3)"},
      {"J8", "%",
       "100 max|u_i - u_ref,i| / max|u_ref,i| for J6's floor (peak error; the benchmark's floor "
       "2)"},
      {"J9", "%", "as J8 for J7's floor (the benchmark's floor 3)"},
  }};
  return definitions;
}

double reported_value(const BenchmarkCriteria& criteria, int number) {
  return number == 1 ? criteria.J(1) * 1e3 : criteria.J(number);
}

std::string criteria_glossary() {
  std::string text =
      "RTHS benchmark criteria (Silva et al. 2020): x_t the command at the experimental DOF, x_m "
      "the displacement measured there, d_ref the reference's drift of that storey, u_ref,i the "
      "reference's floor i (the exact response of the whole structure)\n";
  for (const CriterionDefinition& d : criterion_definitions()) {
    const std::string head = std::string(d.name) + " (" + d.unit + ")";
    text +=
        "  " + head + std::string(head.size() < 9 ? 9 - head.size() : 1, ' ') + d.definition + "\n";
  }
  return text;
}

std::string format_criteria(const BenchmarkCriteria& c) {
  std::string text;
  char buffer[64];
  for (int i = 1; i <= 9; ++i) {
    const double v = c.J(i);
    if (std::isnan(v)) {
      std::snprintf(buffer, sizeof buffer, "%sJ%d n/a", i > 1 ? "  " : "", i);
    } else if (i == 1) {
      std::snprintf(buffer, sizeof buffer, "J1 %.2f ms", v * 1e3);
    } else {
      std::snprintf(buffer, sizeof buffer, "  J%d %.2f %%", i, v);
    }
    text += buffer;
  }
  return text;
}

}  // namespace rths::core
