#include "identify/model/spectra.h"

#include <fftw3.h>
#include <numbers>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numeric>
#include <stdexcept>

#include "core/metrics.h"

namespace rths::identify {
namespace {

std::vector<double> centred(std::span<const double> x) {
  std::vector<double> out(x.begin(), x.end());
  if (out.empty()) return out;
  const double mean = core::mean(out);
  for (double& v : out) v -= mean;
  return out;
}

// Forward real FFT of length n (x zero-padded to n).
std::vector<std::complex<double>> rfft(const std::vector<double>& x, std::size_t n) {
  std::vector<double> in(n, 0.0);
  std::copy_n(x.begin(), std::min(n, x.size()), in.begin());
  std::vector<std::complex<double>> out(n / 2 + 1);
  fftw_plan plan = fftw_plan_dft_r2c_1d(static_cast<int>(n), in.data(),
                                        reinterpret_cast<fftw_complex*>(out.data()), FFTW_ESTIMATE);
  if (plan == nullptr)
    throw std::runtime_error("FFTW could not plan a transform of size " + std::to_string(n));
  fftw_execute(plan);
  fftw_destroy_plan(plan);
  return out;
}

std::vector<double> irfft(std::vector<std::complex<double>> spectrum, std::size_t n) {
  std::vector<double> out(n);
  fftw_plan plan =
      fftw_plan_dft_c2r_1d(static_cast<int>(n), reinterpret_cast<fftw_complex*>(spectrum.data()),
                           out.data(), FFTW_ESTIMATE);
  if (plan == nullptr) throw std::runtime_error("FFTW could not plan an inverse transform");
  fftw_execute(plan);
  fftw_destroy_plan(plan);
  for (double& v : out) v /= static_cast<double>(n);
  return out;
}

}  // namespace

Spectrum amplitude_spectrum(std::span<const double> x, double dt) {
  Spectrum s;
  const std::size_t n = x.size();
  if (n < 2 || !(dt > 0.0)) return s;
  auto w = centred(x);
  double window_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double hann = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) /
                                             static_cast<double>(n - 1));
    w[i] *= hann;
    window_sum += hann;
  }
  const auto spectrum = rfft(w, n);
  s.frequency.resize(spectrum.size());
  s.amplitude.resize(spectrum.size());
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    s.frequency[k] = static_cast<double>(k) / (static_cast<double>(n) * dt);
    s.amplitude[k] = (k == 0 ? 1.0 : 2.0) * std::abs(spectrum[k]) / window_sum;
  }
  return s;
}

double correlation(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size()) throw std::invalid_argument("correlation: different lengths");
  const auto ca = centred(a), cb = centred(b);
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (std::size_t i = 0; i < ca.size(); ++i) {
    ab += ca[i] * cb[i];
    aa += ca[i] * ca[i];
    bb += cb[i] * cb[i];
  }
  return aa > 0.0 && bb > 0.0 ? ab / std::sqrt(aa * bb) : 0.0;
}

CrossCorrelation cross_correlation(std::span<const double> a, std::span<const double> b, double dt,
                                   double max_lag) {
  if (a.size() != b.size()) throw std::invalid_argument("cross_correlation: different lengths");
  CrossCorrelation result;
  const std::size_t n = a.size();
  if (n < 2 || !(dt > 0.0)) return result;
  const auto ca = centred(a), cb = centred(b);
  const double norm = std::sqrt(std::inner_product(ca.begin(), ca.end(), ca.begin(), 0.0) *
                                std::inner_product(cb.begin(), cb.end(), cb.begin(), 0.0));
  if (!(norm > 0.0)) return result;
  std::size_t size = 1;
  while (size < 2 * n) size <<= 1;
  auto fa = rfft(ca, size);
  const auto fb = rfft(cb, size);
  for (std::size_t k = 0; k < fa.size(); ++k) fa[k] = std::conj(fa[k]) * fb[k];
  const auto c = irfft(std::move(fa), size);  // c[l] = sum a_i b_{i+l}, negative l wrap around
  const auto max_l =
      static_cast<long>(std::min<double>(std::floor(max_lag / dt), static_cast<double>(n - 1)));
  const auto at = [&](long l) {
    return c[static_cast<std::size_t>(l >= 0 ? l : static_cast<long>(size) + l)] / norm;
  };
  long best = 0;
  for (long l = -max_l; l <= max_l; ++l) {
    if (std::abs(at(l)) > std::abs(at(best))) best = l;
  }
  double offset = 0.0;
  if (best > -max_l && best < max_l) {
    const double y0 = at(best - 1), y1 = at(best), y2 = at(best + 1);
    const double denom = y0 - 2.0 * y1 + y2;
    if (denom != 0.0) offset = std::clamp(0.5 * (y0 - y2) / denom, -0.5, 0.5);
  }
  result.lag = (static_cast<double>(best) + offset) * dt;
  result.peak = at(best);
  return result;
}

namespace {

// Welch sums over segments of `segment` samples, 50 % overlap, mean removed, Hann window:
// S_xx, S_yy (bins 0 .. segment/2) and S_xy = sum conj(X) Y. Unnormalised (ratios only).
struct WelchSums {
  std::vector<double> sxx, syy;
  std::vector<std::complex<double>> sxy;
  std::size_t segments = 0;
};

WelchSums welch_sums(std::span<const double> x, std::span<const double> y, std::size_t segment) {
  const std::size_t bins = segment / 2 + 1, hop = segment / 2;
  std::vector<double> window(segment);
  for (std::size_t i = 0; i < segment; ++i) {
    window[i] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) /
                                     static_cast<double>(segment - 1));
  }
  WelchSums out;
  out.sxx.assign(bins, 0.0);
  out.syy.assign(bins, 0.0);
  out.sxy.assign(bins, 0.0);
  const auto windowed = [&](std::span<const double> part) {
    auto c = centred(part);
    for (std::size_t i = 0; i < segment; ++i) c[i] *= window[i];
    return rfft(c, segment);
  };
  for (std::size_t start = 0; start + segment <= x.size(); start += hop) {
    const auto fx = windowed(x.subspan(start, segment));
    const auto fy = windowed(y.subspan(start, segment));
    for (std::size_t k = 0; k < bins; ++k) {
      out.sxx[k] += std::norm(fx[k]);
      out.syy[k] += std::norm(fy[k]);
      out.sxy[k] += std::conj(fx[k]) * fy[k];
    }
    ++out.segments;
  }
  return out;
}

}  // namespace

TransferEstimate transfer_estimate(std::span<const double> x, std::span<const double> y, double dt,
                                   std::size_t segment) {
  if (x.size() != y.size() || segment < 8 || x.size() < segment || !(dt > 0.0)) {
    throw std::invalid_argument(
        "transfer_estimate: need two series of equal length >= the segment (" +
        std::to_string(segment) + " >= 8 samples) and dt > 0");
  }
  const WelchSums w = welch_sums(x, y, segment);
  TransferEstimate out;
  out.segments = w.segments;
  double previous = 0.0;
  for (std::size_t k = 1; k < w.sxx.size(); ++k) {
    out.frequency.push_back(static_cast<double>(k) / (static_cast<double>(segment) * dt));
    const std::complex<double> h = w.sxx[k] > 0.0 ? w.sxy[k] / w.sxx[k] : 0.0;
    out.magnitude.push_back(std::abs(h));
    double phase = std::arg(h);
    if (k > 1) phase = previous + std::remainder(phase - previous, 2.0 * std::numbers::pi);
    out.phase.push_back(phase);
    previous = phase;
    const double denominator = w.sxx[k] * w.syy[k];
    out.coherence.push_back(denominator > 0.0 ? std::min(1.0, std::norm(w.sxy[k]) / denominator)
                                              : 0.0);
  }
  return out;
}

double noise_edge(std::span<const double> x, double dt) {
  const double band = signal_band(x, dt);
  if (x.size() < 512 || !(band > 0.0)) return 0.0;
  std::size_t segment = 256;
  while (segment * 2 <= x.size() / 8 && segment < 4096) segment *= 2;
  const WelchSums w = welch_sums(x, x, segment);
  const double df = 1.0 / (static_cast<double>(segment) * dt), nyquist = 0.5 / dt;
  if (!(1.5 * band < 0.9 * nyquist)) return 0.0;
  std::vector<double> above;
  for (std::size_t k = 1; k < w.sxx.size(); ++k) {
    if (static_cast<double>(k) * df > 1.5 * band) above.push_back(w.sxx[k]);
  }
  if (above.empty()) return 0.0;
  std::nth_element(above.begin(), above.begin() + static_cast<std::ptrdiff_t>(above.size() / 2),
                   above.end());
  const double noise = above[above.size() / 2];
  if (!(noise > 0.0)) return 0.0;
  // The first bin above the band whose 5-bin average has sunk to 10 x the noise density.
  for (std::size_t k = 3; k + 2 < w.sxx.size(); ++k) {
    if (static_cast<double>(k) * df <= band) continue;
    double mean = 0.0;
    for (std::size_t j = k - 2; j <= k + 2; ++j) mean += w.sxx[j] / 5.0;
    if (mean <= 10.0 * noise) return static_cast<double>(k) * df;
  }
  return nyquist;
}

double signal_band(std::span<const double> x, double dt) {
  if (x.size() < 16 || !(dt > 0.0)) return 0.0;
  const Spectrum in = amplitude_spectrum(x, dt);
  double total = 0.0;
  for (std::size_t k = 1; k < in.amplitude.size(); ++k) total += in.amplitude[k] * in.amplitude[k];
  if (!(total > 0.0)) return 0.0;
  double cumulative = 0.0;
  for (std::size_t k = 1; k < in.amplitude.size(); ++k) {
    cumulative += in.amplitude[k] * in.amplitude[k];
    if (cumulative >= 0.995 * total) return in.frequency[k];
  }
  return in.frequency.back();
}

double noise_floor(std::span<const double> input, std::span<const double> target, double dt) {
  if (input.size() != target.size() || target.size() < 16 || !(dt > 0.0)) return 0.0;
  const Spectrum out = amplitude_spectrum(target, dt);
  const double band = signal_band(input, dt);
  const double nyquist = out.frequency.back(), cut = 1.5 * (band > 0.0 ? band : nyquist);
  if (!(cut < 0.9 * nyquist)) return 0.0;  // no band free of signal: nothing to estimate from
  double above = 0.0, total = 0.0;
  for (std::size_t k = 1; k < out.amplitude.size(); ++k) {
    const double power = out.amplitude[k] * out.amplitude[k];
    total += power;
    if (out.frequency[k] > cut) above += power;
  }
  return total > 0.0 ? std::sqrt(above * nyquist / (nyquist - cut) / total) : 0.0;
}

}  // namespace rths::identify
