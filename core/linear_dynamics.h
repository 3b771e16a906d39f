#pragma once
// A block's own linear dynamics, as stability analysis and compensator design read them: every
// delay stage (core/delay.h), tracking loop (core/tracking.h), compensator
// (core/compensation.h) and a DelayChain of them states its dynamics through LinearDynamics, so
// an analysis never needs to know which concrete block it holds.
//
// Input u (m, the command the block receives), output y (m, what it hands on), one call per step
// of dt (s), the step the block was built for.
//
// LinearDynamics:
//   linearity()            whether the block is linear time-invariant (kTimeInvariant),
//   time-varying
//                          but stated at its present coefficients (kFrozen: an adapting block),
//                          linear once a non-linear part is left out (kLinearised: saturating or
//                          quantising converters), or not representable (kNone); `note` says
//                          what was frozen or left out, or why not.
//   frequency_response(w)  H(i w), w in rad/s: the block's transfer function on the imaginary axis
//                          (its continuous description where it has one, e.g. e^{-i w tau}; for a
//                          block defined in discrete time, H(z) at z = e^{i w dt}).
//   state_space()          its discrete realisation at dt: x[k+1] = A x[k] + B u[k],
//                          y[k] = C x[k] + D u[k] (single input and output; x at rest = 0).
//   transfer_function()    the block as g e^{-s tau} N(s) / D(s) when it has that form (empty
//                          otherwise); a series of such blocks is again one, which lets a chain
//                          evaluate its H as one rational function with one delay.
// frequency_response and state_space throw std::invalid_argument with the note for kNone.
//
// Helpers: series(P, Q) is Q after P (y = Q(P(u))); gain_block(g) y = g u; fir_block(d, taps)
// y[k] = d u[k] + sum_j taps[j] u[k - 1 - j]; shift_block(tau, dt) u(t - tau) interpolated
// linearly between two register taps (tau = (n + w) dt: (1 - w) u[k - n] + w u[k - n - 1]);
// direct_form_block(b, a) the direct form II transposed filter b(z^-1) / a(z^-1) (a[0] = 1, b
// and a of equal length); response_at(block, z) = C (z I - A)^-1 B + D.

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "core/structure.h"

namespace rths::core {

// x+ = a x + b u,  y = c x + d u (discrete, single input and output).
struct LinearBlock {
  Mat a;
  Vec b;
  Eigen::RowVectorXd c;
  double d = 1.0;
  int states() const { return static_cast<int>(a.rows()); }
};
LinearBlock series(const LinearBlock& first, const LinearBlock& second);
// A block of `states` states whose A, B and C are zero, with feedthrough `d`: the start of a
// block whose parts are then placed.
LinearBlock zero_block(int states, double d);
LinearBlock gain_block(double gain);
LinearBlock fir_block(double d, const std::vector<double>& taps);
// @pre delay >= 0, dt > 0 (throws std::invalid_argument).
LinearBlock shift_block(double delay, double dt);
// @pre a.size() == b.size() >= 1, a[0] == 1.
LinearBlock direct_form_block(const std::vector<double>& b, const std::vector<double>& a);
std::complex<double> response_at(const LinearBlock& block, std::complex<double> z);

// Polynomials, coefficients highest power first: p(s) (Horner), the product a b, and p without
// its leading zero coefficients (at least one coefficient kept).
std::complex<double> polynomial_at(const std::vector<double>& p, std::complex<double> s);
std::vector<double> polynomial_multiply(const std::vector<double>& a, const std::vector<double>& b);
std::vector<double> trimmed(std::vector<double> p);

// A continuous block g e^{-s delay} N(s) / D(s), coefficients highest power of s first.
struct PlantModel {
  double delay = 0.0;  // s, >= 0
  double gain = 1.0;
  std::vector<double> numerator{1.0}, denominator{1.0};
  void append(const std::vector<double>& num, const std::vector<double>& den);  // G *= num/den
  void append(const PlantModel& other);  // G *= other: gains multiply, delays add
  std::string describe() const;
  std::complex<double> at(double omega) const;  // G(i omega), omega in rad/s
};

struct Linearity {
  enum class Kind { kTimeInvariant, kFrozen, kLinearised, kNone };
  Kind kind = Kind::kTimeInvariant;
  std::string note;  // empty for kTimeInvariant
  bool analysable() const { return kind != Kind::kNone; }
};

class LinearDynamics {
 public:
  virtual ~LinearDynamics() = default;
  virtual Linearity linearity() const = 0;
  virtual std::complex<double> frequency_response(double omega) const = 0;
  virtual LinearBlock state_space() const = 0;
  virtual std::optional<PlantModel> transfer_function() const { return std::nullopt; }
};

}  // namespace rths::core
