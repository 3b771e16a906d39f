#include "identify/residual/drift_shape.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace rths::identify {
namespace {

struct Line {
  double a = 0.0, b = 0.0, sse = 0.0;  // v = a + b x
};

// Least squares v = a + b x over the windows; b = 0 when x does not vary.
Line fit_line(std::span<const double> x, std::span<const double> v) {
  const auto n = static_cast<double>(x.size());
  double mx = 0.0, mv = 0.0;
  for (std::size_t w = 0; w < x.size(); ++w) {
    mx += x[w] / n;
    mv += v[w] / n;
  }
  double sxx = 0.0, sxv = 0.0;
  for (std::size_t w = 0; w < x.size(); ++w) {
    sxx += (x[w] - mx) * (x[w] - mx);
    sxv += (x[w] - mx) * (v[w] - mv);
  }
  Line out;
  out.b = sxx > 0.0 ? sxv / sxx : 0.0;
  out.a = mv - out.b * mx;
  for (std::size_t w = 0; w < x.size(); ++w) {
    const double e = v[w] - out.a - out.b * x[w];
    out.sse += e * e;
  }
  return out;
}

struct Step {
  double before = 0.0, after = 0.0, time = 0.0, sse = std::numeric_limits<double>::infinity();
};

// The best split into two levels, between windows s - 1 and s (s = 1 .. n - 1).
Step fit_step(std::span<const double> t, std::span<const double> v) {
  Step best;
  for (std::size_t s = 1; s < v.size(); ++s) {
    double before = 0.0, after = 0.0;
    for (std::size_t w = 0; w < v.size(); ++w) (w < s ? before : after) += v[w];
    before /= static_cast<double>(s);
    after /= static_cast<double>(v.size() - s);
    double sse = 0.0;
    for (std::size_t w = 0; w < v.size(); ++w) {
      const double e = v[w] - (w < s ? before : after);
      sse += e * e;
    }
    if (sse < best.sse) best = {before, after, 0.5 * (t[s - 1] + t[s]), sse};
  }
  return best;
}

struct Exponential {
  Line line;  // over x = exp(-(t - t_1) / tau)
  double tau = 0.0;
};

Exponential fit_exponential(std::span<const double> t, std::span<const double> v) {
  const double span = t.back() - t.front();
  Exponential best;
  best.line.sse = std::numeric_limits<double>::infinity();
  std::vector<double> x(t.size());
  for (std::size_t g = 0; g < kExponentialGrid; ++g) {
    const double share = static_cast<double>(g) / static_cast<double>(kExponentialGrid - 1);
    const double tau = span / 20.0 * std::pow(40.0, share);
    for (std::size_t w = 0; w < t.size(); ++w) x[w] = std::exp(-(t[w] - t.front()) / tau);
    if (const Line line = fit_line(x, v); line.sse < best.line.sse) best = {line, tau};
  }
  return best;
}

}  // namespace

ShapeFit fit_shape(std::span<const double> time, std::span<const double> value) {
  if (time.size() != value.size() || time.size() < 4 || !(time.back() > time.front()))
    throw std::invalid_argument("fit_shape: at least 4 windows of increasing time, one value each");
  const Line line = fit_line(time, value);
  const Step step = fit_step(time, value);
  const Exponential exponential = fit_exponential(time, value);
  ShapeFit out;
  out.first = time.front();
  out.last = time.back();
  out.sse_linear = line.sse;
  out.sse_step = step.sse;
  out.sse_exponential = exponential.line.sse;
  out.start = line.a + line.b * time.front();
  out.end = line.a + line.b * time.back();
  const double least = std::min(step.sse, exponential.line.sse);
  if (!(least <= kShapeWins * line.sse)) return out;
  if (step.sse <= exponential.line.sse) {
    out.shape = DriftShape::kStep;
    out.start = step.before;
    out.end = step.after;
    out.at = step.time;
    return out;
  }
  const double decayed = std::exp(-(time.back() - time.front()) / exponential.tau);
  out.shape = DriftShape::kExponential;
  out.start = exponential.line.a + exponential.line.b;
  out.end = exponential.line.a + exponential.line.b * decayed;
  out.at = exponential.tau;
  return out;
}

double ShapeFit::value_at(double t) const {
  switch (shape) {
    case DriftShape::kStep: return t < at ? start : end;
    case DriftShape::kExponential: {
      const double b = (start - end) / (1.0 - std::exp(-(last - first) / at));
      return start - b + b * std::exp(-(t - first) / at);
    }
    case DriftShape::kLinear: break;
  }
  return start + (end - start) * (t - first) / (last - first);
}

std::string shape_name(DriftShape shape) {
  switch (shape) {
    case DriftShape::kStep: return "step";
    case DriftShape::kExponential: return "exponential";
    case DriftShape::kLinear: break;
  }
  return "linear";
}

}  // namespace rths::identify
