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
// or the exponential's time constant (s).

#include <cstddef>
#include <span>
#include <string>

namespace rths::identify {

inline constexpr double kShapeWins = 0.5;  // of the line's sum of squares
inline constexpr std::size_t kExponentialGrid = 40;

enum class DriftShape { kLinear, kStep, kExponential };

struct ShapeFit {
  DriftShape shape = DriftShape::kLinear;
  double start = 0.0, end = 0.0;  // the value's unit, at the first and last window centre
  double at = 0.0;                // s: the step's time, the exponential's time constant; 0: line
  double sse_linear = 0.0, sse_step = 0.0, sse_exponential = 0.0;  // unit^2
};

// @pre time and value of the same size, at least 4 windows, time increasing.
ShapeFit fit_shape(std::span<const double> time, std::span<const double> value);

// "linear", "step", "exponential".
std::string shape_name(DriftShape shape);

}  // namespace rths::identify
