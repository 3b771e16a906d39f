#include "identify/model/signals.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "core/metrics.h"
#include "identify/model/spectra.h"

namespace rths::identify {
namespace {

// The population standard deviation (core/metrics.h), 0 for a signal the record lacks (empty).
double rms_about_mean(std::span<const double> x) {
  return x.empty() ? 0.0 : core::standard_deviation(x);
}

std::vector<double> moving_average(std::span<const double> x, std::size_t window) {
  const std::size_t n = x.size();
  std::vector<double> out(n);
  if (window <= 1) {
    std::copy(x.begin(), x.end(), out.begin());
    return out;
  }
  const std::size_t half = window / 2;
  std::vector<double> prefix(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + x[i];
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t lo = i >= half ? i - half : 0;
    const std::size_t hi = std::min(n, i + half + 1);
    out[i] = (prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo);
  }
  return out;
}

std::vector<double> central_difference(std::span<const double> x, double dt) {
  const std::size_t n = x.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  for (std::size_t i = 1; i + 1 < n; ++i) d[i] = (x[i + 1] - x[i - 1]) / (2.0 * dt);
  d[0] = (x[1] - x[0]) / dt;
  d[n - 1] = (x[n - 1] - x[n - 2]) / dt;
  return d;
}

}  // namespace

double drift_profile(std::span<const double> c, double s) {
  double sum = 0.0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    sum += c[k] * std::cos(std::numbers::pi * static_cast<double>(k + 1) * (s + 0.5));
  }
  return sum;
}

std::vector<double> drift_basis(std::span<const double> time, double dt) {
  std::vector<double> basis(time.size() * kDriftTerms);
  if (time.empty()) return basis;
  const double t_mid = 0.5 * (time.front() + time.back());
  const double duration = std::max(time.back() - time.front(), dt);
  for (std::size_t j = 0; j < time.size(); ++j) {
    const double s = (time[j] - t_mid) / duration;
    for (std::size_t k = 0; k < kDriftTerms; ++k) {
      basis[j * kDriftTerms + k] =
          std::cos(std::numbers::pi * static_cast<double>(k + 1) * (s + 0.5));
    }
  }
  return basis;
}

std::vector<double> zero_phase_lowpass(std::span<const double> x, double dt, double cutoff) {
  if (!(dt > 0.0) || !(cutoff > 0.0) || !(cutoff < 0.5 / dt)) {
    throw std::invalid_argument("zero_phase_lowpass: need 0 < cutoff < Nyquist (cutoff " +
                                std::to_string(cutoff) + " Hz, dt " + std::to_string(dt) + " s)");
  }
  std::vector<double> y(x.begin(), x.end());
  if (y.empty()) return y;
  const double w = std::tan(std::numbers::pi * cutoff * dt);  // pre-warped analogue cut-off
  const auto section = [&](double q) {
    const double norm = 1.0 / (1.0 + w / q + w * w);
    const double b0 = w * w * norm, b1 = 2.0 * b0, b2 = b0;
    const double a1 = 2.0 * (w * w - 1.0) * norm, a2 = (1.0 - w / q + w * w) * norm;
    // Direct form II transposed, at rest with input y[0] (DC gain 1).
    double s2 = (b2 - a2) * y.front();
    double s1 = (b1 - a1) * y.front() + s2;
    for (double& v : y) {
      const double out = b0 * v + s1;
      s1 = b1 * v - a1 * out + s2;
      s2 = b2 * v - a2 * out;
      v = out;
    }
  };
  const double q1 = 1.0 / (2.0 * std::cos(std::numbers::pi / 8.0));
  const double q2 = 1.0 / (2.0 * std::cos(3.0 * std::numbers::pi / 8.0));
  for (int pass = 0; pass < 2; ++pass) {
    section(q1);
    section(q2);
    std::reverse(y.begin(), y.end());
  }
  return y;
}

ChannelSignals make_signals(const MeasuredData& data, Channel channel, double smooth_window) {
  ChannelSignals s;
  s.channel = channel;
  s.dt = data.dt;
  s.time = data.time;
  s.input = channel == Channel::kMeasured ? data.command : data.measured;
  s.target = channel == Channel::kMeasured ? data.measured : data.force;
  if (channel == Channel::kForce && s.input.size() >= 16) {
    const double edge = noise_edge(s.input, data.dt);
    const double cutoff =
        edge > 0.0 ? std::max(kSpecimenInputCutoffFactor * signal_band(s.input, data.dt), edge)
                   : 0.0;
    if (cutoff > 0.0 && cutoff < 0.8 * 0.5 / data.dt) {
      s.model_input = zero_phase_lowpass(s.input, data.dt, cutoff);
      s.input_cutoff = cutoff;
    }
  }
  const std::vector<double>& drive = s.model_input.empty() ? s.input : s.model_input;
  const auto window = static_cast<std::size_t>(std::max(1.0, std::round(smooth_window / data.dt)));
  const auto smooth = moving_average(drive, window);
  s.velocity = central_difference(smooth, data.dt);
  s.acceleration = central_difference(moving_average(s.velocity, window), data.dt);
  s.drift_basis = drift_basis(s.time, s.dt);
  static std::atomic<std::uint64_t> next_id{1};
  s.id = next_id.fetch_add(1);
  return s;
}

SignalScales signal_scales(const ChannelSignals& signals) {
  SignalScales sc;
  const auto positive = [](double v, double fallback) { return v > 0.0 ? v : fallback; };
  sc.input = positive(rms_about_mean(signals.input), 1.0e-3);
  sc.velocity = positive(rms_about_mean(signals.velocity), sc.input);
  sc.acceleration = positive(rms_about_mean(signals.acceleration), sc.velocity);
  sc.target = positive(rms_about_mean(signals.target), 1.0);
  double peak = 0.0;
  for (double x : signals.target) peak = std::max(peak, std::abs(x));
  sc.target_peak = positive(peak, sc.target);
  sc.dt = signals.dt;
  sc.duration = signals.size() > 1 ? signals.time.back() - signals.time.front() : 1.0;
  if (!(sc.duration > 0.0)) sc.duration = 1.0;
  return sc;
}

}  // namespace rths::identify
