#pragma once
// The shape of a value that moves over a record, from its values in windows (a gain, a stiffness,
// a delay fitted window by window): slow changes reported as changes, not as one constant.
//
// Input: window centres t_w (s, increasing) and the value v_w in each (any unit), w = 1..n.
// Three shapes are fitted by least squares over the windows:
//   linear       v = a + b t                                      (2 parameters)
//   step         v = v_before for t < t_s, v_after from t_s on    (3: t_s between two windows)
//   exponential  v = a + b exp(-(t - t_1) / tau)                  (3: tau on a grid of
//                kExponentialGrid values log-spaced from a twentieth to twice the span; a and
//                b by least squares at each)
// The line is kept unless the step or the exponential leaves at most kShapeWins x its sum of
// squares (the one that leaves less then): a shape earns its third parameter. The fitted shape
// gives the value at the first and last window centre (start, end); `at` is the step's time (s)
// or the exponential's time constant (s). value_at(t) is the fitted shape at any time t (s): the
// line and the exponential run on beyond the first and last centre, the step holds its levels.

#include <cstddef>
#include <span>
#include <string>

namespace rths::identify {

inline constexpr double kShapeWins = 0.5;  // of the line's sum of squares
inline constexpr std::size_t kExponentialGrid = 40;

enum class DriftShape { kLinear, kStep, kExponential };

struct ShapeFit {
  DriftShape shape = DriftShape::kLinear;
  double start = 0.0, end = 0.0;   // the value's unit, at the first and last window centre
  double at = 0.0;                 // s: the step's time, the exponential's time constant; 0: line
  double first = 0.0, last = 0.0;  // s: the first and last window centre
  double sse_linear = 0.0, sse_step = 0.0, sse_exponential = 0.0;  // unit^2
  // The value's unit at time t (s):
  //   linear       start + (end - start) (t - first) / (last - first)
  //   step         start for t < at, end from at on
  //   exponential  a + b exp(-(t - first) / at), b = (start - end) / (1 - exp(-(last - first) /
  //                at)), a = start - b
  double value_at(double t) const;
};

// @pre time and value of the same size, at least 4 windows, time increasing.
ShapeFit fit_shape(std::span<const double> time, std::span<const double> value);

// "linear", "step", "exponential".
std::string shape_name(DriftShape shape);

}  // namespace rths::identify
