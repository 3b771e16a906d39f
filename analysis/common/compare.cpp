#include "analysis/common/compare.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "core/envelope_growth.h"
#include "core/metrics.h"

namespace rths::analysis {

ResponseSpec ResponseSpec::floor(int one_based) {
  if (one_based < 1)
    throw std::invalid_argument("response floor must be >= 1, got " + std::to_string(one_based));
  return ResponseSpec(one_based);
}

std::string ResponseSpec::describe() const {
  return is_floor() ? "floor " + std::to_string(floor_) : "peak over floors";
}

std::vector<int> ResponseSpec::columns(int dofs) const {
  if (!is_floor()) {
    std::vector<int> all(static_cast<std::size_t>(dofs));
    for (int i = 0; i < dofs; ++i) all[static_cast<std::size_t>(i)] = i;
    return all;
  }
  if (floor_ > dofs) {
    throw std::invalid_argument("response " + describe() + " does not exist: the structure has " +
                                std::to_string(dofs) + " floor(s)");
  }
  return {floor_ - 1};
}

nlohmann::json Comparison::to_json() const {
  return {{"response", response},
          {"steps_compared", steps_compared},
          {"reference_steps", reference_steps},
          {"peak_reference_m", peak_reference_m},
          {"peak_m", peak_m},
          {"peak_error_m", peak_error_m},
          {"peak_error_pct", peak_error_pct},
          {"rms_error_pct", rms_error_pct},
          {"nrmse_pct", nrmse_pct},
          {"paper_eq2_as_printed", paper_eq2_as_printed},
          {"diverged", diverged}};
}

std::vector<double> floor_history(const core::SimulationResult& result, int dof) {
  const Eigen::Index column = result.column_of_dof(dof);
  if (column < 0)
    throw std::invalid_argument("the run kept no history of DOF " + std::to_string(dof + 1) +
                                " (add it to a recorder)");
  std::vector<double> u(result.steps());
  for (std::size_t k = 0; k < u.size(); ++k)
    u[k] = result.displacement(static_cast<Eigen::Index>(k), column);
  return u;
}

std::vector<double> column_of(const core::Mat& history, int column) {
  std::vector<double> out(static_cast<std::size_t>(history.rows()));
  for (Eigen::Index i = 0; i < history.rows(); ++i)
    out[static_cast<std::size_t>(i)] = history(i, column);
  return out;
}

Comparison compare(std::span<const double> reference, std::span<const double> result,
                   bool stopped_early) {
  const std::size_t n = std::min(reference.size(), result.size());
  if (n == 0) throw std::invalid_argument("compare: an empty history");
  const auto r = reference.first(n), x = result.first(n);
  Comparison c;
  c.steps_compared = n;
  c.reference_steps = reference.size();
  c.peak_reference_m = core::peak_abs(r);
  c.peak_m = core::peak_abs(result);
  c.peak_error_m = core::peak_error(r, x);
  c.peak_error_pct = core::relative_peak_error_pct(r, x);
  c.rms_error_pct = core::relative_rms_error_pct(r, x);
  c.nrmse_pct = 100.0 * core::nrmse(r, x);
  c.paper_eq2_as_printed = core::paper_eq2(r, x);
  c.diverged = stopped_early || core::grew_past_reference(c.peak_reference_m, c.peak_m);
  return c;
}

Comparison compare(const core::SimulationResult& reference, const core::SimulationResult& result,
                   const ResponseSpec& response) {
  if (reference.displacement.cols() != result.displacement.cols() ||
      reference.dofs != result.dofs) {
    throw std::invalid_argument("compare: the reference has " +
                                std::to_string(reference.displacement.cols()) +
                                " floors, the case " + std::to_string(result.displacement.cols()));
  }
  Comparison worst;
  bool first = true;
  // The model's DOFs: the top one is always kept (study/recorders.h).
  const int dofs =
      result.dofs.empty() ? static_cast<int>(result.displacement.cols()) : result.dofs.back() + 1;
  for (int dof : response.columns(dofs)) {
    if (result.column_of_dof(dof) < 0) continue;  // peak over floors: over the kept ones
    const Comparison c =
        compare(floor_history(reference, dof), floor_history(result, dof), result.diverged);
    if (first) {
      worst = c;
      first = false;
      continue;
    }
    // NaN-aware max: a non-finite floor must win.
    const auto worse = [](double a, double b) { return std::isnan(b) || b > a ? b : a; };
    worst.peak_reference_m = worse(worst.peak_reference_m, c.peak_reference_m);
    worst.peak_m = worse(worst.peak_m, c.peak_m);
    worst.peak_error_m = worse(worst.peak_error_m, c.peak_error_m);
    worst.peak_error_pct = worse(worst.peak_error_pct, c.peak_error_pct);
    worst.rms_error_pct = worse(worst.rms_error_pct, c.rms_error_pct);
    worst.nrmse_pct = worse(worst.nrmse_pct, c.nrmse_pct);
    worst.paper_eq2_as_printed = worse(worst.paper_eq2_as_printed, c.paper_eq2_as_printed);
    worst.diverged = worst.diverged || c.diverged;
  }
  worst.response = response.describe();
  return worst;
}

bool diverging(std::span<const double> u, double dt, double period, bool past_critical_delay) {
  if (!past_critical_delay || !(dt > 0.0) || !(period > 0.0)) return false;
  const std::optional<core::EnvelopeGrowth> growth = core::envelope_growth(u, dt, period);
  return growth && growth->grows();
}

}  // namespace rths::analysis
