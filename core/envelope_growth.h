#pragma once
// Exponential growth of a response's envelope over its last cycles: how a lagged hybrid test that
// is past its critical delay is told from one that is merely amplified.
//
// Input: a history u (any unit) sampled at dt (s), and the period (s) of the mode whose growth is
// judged (a check's governing mode). The fitted part is the last kFittedShare of the record, but
// at least kMinWindows periods when the record has them; it is cut into whole windows of one
// period ending at the last sample, and each window's peak |u| is its envelope value.
// Fit: least squares of ln(peak) against the window's centre time, so peak ~ exp(rate t):
//   rate (1/s)           > 0 grows, < 0 decays
//   doubling_time (s)    ln 2 / rate (meaningful when rate > 0)
//   r_squared            the fit's coefficient of determination, 1 for a clean exponential
//   span (s)             windows x period
// grows(): the envelope grows exponentially, i.e. rate > 0, the fit explains at least
// kMinRSquared of ln(peak)'s variance (growth, not one late burst of forcing), and the fitted
// envelope at least doubles over the span (rate span >= ln 2). A stable test's free vibration at
// the end of a record decays (rate ~ -zeta omega) and never passes.
// Empty (std::nullopt) when the history holds fewer than kMinWindows whole periods, is not finite
// in the fitted part, or has a window whose peak is 0 (no envelope to take a logarithm of).
// Throws std::invalid_argument when dt or period is not > 0.

#include <optional>
#include <span>

namespace rths::core {

struct EnvelopeGrowth {
  static constexpr double kFittedShare = 1.0 / 3.0;
  static constexpr int kMinWindows = 6;
  static constexpr double kMinRSquared = 0.8;
  double rate = 0.0;           // 1/s
  double doubling_time = 0.0;  // s; +inf when rate <= 0
  double r_squared = 0.0;
  double span = 0.0;  // s
  int windows = 0;
  double period = 0.0;  // s, one window
  bool grows() const;
};

std::optional<EnvelopeGrowth> envelope_growth(std::span<const double> u, double dt, double period);

}  // namespace rths::core
