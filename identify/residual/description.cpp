#include "identify/residual/description.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "identify/model/spectra.h"

namespace rths::identify {
namespace {

using Samples = std::vector<std::size_t>;

// The alternate windows: even ones train, odd ones are held out.
struct Halves {
  Samples train, heldout;
  std::vector<std::size_t> window;  // of each sample
};

Halves alternate_windows(std::size_t n) {
  Halves out;
  out.window.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    out.window[j] = std::min(kDescriptionWindows - 1, j * kDescriptionWindows / n);
    (out.window[j] % 2 == 0 ? out.train : out.heldout).push_back(j);
  }
  return out;
}

double mean_over(std::span<const double> x, const Samples& at) {
  double sum = 0.0;
  for (std::size_t j : at) sum += x[j];
  return at.empty() ? 0.0 : sum / static_cast<double>(at.size());
}

// Sum of squares about the mean over `at`.
double spread_over(std::span<const double> x, const Samples& at) {
  const double m = mean_over(x, at);
  double sum = 0.0;
  for (std::size_t j : at) sum += (x[j] - m) * (x[j] - m);
  return sum;
}

// 1 - var_h(r - d) / var_h(r): the held-out share of r's variance d explains.
double explained(std::span<const double> r, std::span<const double> d, const Samples& heldout) {
  const double total = spread_over(r, heldout);
  return total > 0.0 ? 1.0 - spread_over(minus(r, d), heldout) / total : 0.0;
}

// |sum r_j exp(-2 pi i f t_j)| over the train samples.
double projection(std::span<const double> time, std::span<const double> r, double f) {
  std::complex<double> sum = 0.0;
  for (std::size_t j = 0; j < r.size(); ++j)
    sum += r[j] * std::polar(1.0, -2.0 * std::numbers::pi * f * time[j]);
  return std::abs(sum);
}

// Whether value(peak) is at least kPeakOverFloor x the median of value(k) over the bins within
// kFloorBand Hz of the peak, leaving out the Hann window's main lobe beside it (a negative value
// is no bin: an input with no amplitude there).
template <class Value>
bool stands_out(const std::vector<double>& frequency, std::size_t peak, const Value& value) {
  constexpr std::size_t kGuard = 3;  // bins
  std::vector<double> around;
  for (std::size_t k = 1; k < frequency.size(); ++k)
    if (std::abs(frequency[k] - frequency[peak]) <= kFloorBand &&
        (k + kGuard < peak || k > peak + kGuard) && value(k) >= 0.0)
      around.push_back(value(k));
  if (around.empty()) return false;
  std::nth_element(around.begin(), around.begin() + static_cast<long>(around.size() / 2),
                   around.end());
  return value(peak) >= kPeakOverFloor * around[around.size() / 2];
}

// Whether a residual's peak at bin `peak` is a period of another source: where the input's own
// spectrum is large there, the residual must stand out of it too (a model's error on the input
// follows the input's spectrum and is the maps' to judge).
bool not_the_inputs(const Spectrum& s, const Spectrum& input, std::size_t peak) {
  const auto over_input = [&](std::size_t k) {
    return input.amplitude[k] > 0.0 ? s.amplitude[k] / input.amplitude[k] : -1.0;
  };
  const double input_peak = *std::max_element(input.amplitude.begin(), input.amplitude.end());
  return input.amplitude[peak] <= kInputPeakShare * input_peak ||
         (input.amplitude[peak] > 0.0 && stands_out(s.frequency, peak, over_input));
}

// The frequency of the largest projection within a bin of `peak`, on a tenth of a bin.
double refined(std::span<const double> time, std::span<const double> r, const Spectrum& s,
               std::size_t peak) {
  const double bin = s.frequency[1] - s.frequency[0];
  double best = s.frequency[peak], best_value = 0.0;
  for (int i = -10; i <= 10; ++i) {
    const double f = s.frequency[peak] + 0.1 * i * bin;
    if (const double v = projection(time, r, f); v > best_value) {
      best_value = v;
      best = f;
    }
  }
  return best;
}

// The spectrum's highest peak above kMinPeriodicFrequency when it stands kPeakOverFloor above
// the median of its neighbourhood, refined to a tenth of a bin; 0 when none stands out.
double spectral_peak(std::span<const double> time, std::span<const double> r,
                     std::span<const double> p, double dt) {
  const Spectrum s = amplitude_spectrum(r, dt);
  const Spectrum input = amplitude_spectrum(p, dt);
  if (s.frequency.size() < 8) return 0.0;
  std::size_t peak = 0;
  for (std::size_t k = 1; k < s.frequency.size(); ++k)
    if (s.frequency[k] >= kMinPeriodicFrequency && s.amplitude[k] > s.amplitude[peak]) peak = k;
  if (peak == 0) return 0.0;
  const auto amplitude = [&](std::size_t k) { return s.amplitude[k]; };
  if (!stands_out(s.frequency, peak, amplitude) || !not_the_inputs(s, input, peak)) return 0.0;
  return refined(time, r, s, peak);
}

// a cos + b sin at `frequency` by least squares over the train samples (means removed), at every
// sample.
std::vector<double> sinusoid(std::span<const double> time, std::span<const double> r,
                             double frequency, const Samples& train, double& amplitude) {
  const double w = 2.0 * std::numbers::pi * frequency, m = mean_over(r, train);
  double cc = 0.0, ss = 0.0, cs = 0.0, rc = 0.0, rs = 0.0;
  for (std::size_t j : train) {
    const double c = std::cos(w * time[j]), s = std::sin(w * time[j]);
    cc += c * c;
    ss += s * s;
    cs += c * s;
    rc += (r[j] - m) * c;
    rs += (r[j] - m) * s;
  }
  const double det = cc * ss - cs * cs;
  const double a = det > 0.0 ? (rc * ss - rs * cs) / det : 0.0;
  const double b = det > 0.0 ? (rs * cc - rc * cs) / det : 0.0;
  amplitude = std::hypot(a, b);
  std::vector<double> out(r.size());
  for (std::size_t j = 0; j < r.size(); ++j)
    out[j] = a * std::cos(w * time[j]) + b * std::sin(w * time[j]);
  return out;
}

// The frequency within a bin of `peak`, on a twentieth of a bin, whose sinusoid fitted on the
// train samples leaves the least of them: with the held-out windows out, a period of a few
// cycles is no longer orthogonal to its neighbours, so the projection alone pulls it off.
double fitted_frequency(std::span<const double> time, std::span<const double> r, const Spectrum& s,
                        std::size_t peak, const Samples& train) {
  const double bin = s.frequency[1] - s.frequency[0];
  double best = s.frequency[peak], least = spread_over(r, train);
  for (int i = -20; i <= 20; ++i) {
    const double f = s.frequency[peak] + 0.05 * i * bin;
    double amplitude = 0.0;
    const double left = spread_over(minus(r, sinusoid(time, r, f, train, amplitude)), train);
    if (f > 0.0 && left < least) {
      least = left;
      best = f;
    }
  }
  return best;
}

// The slow band's peak (description.h periodic): r is the train samples less their line. The
// highest bin from kMinPeriodicCycles in the record up to kMinPeriodicFrequency, taken only where
// the spectrum rises to it from every bin below it (a drift's spectrum, of what a line leaves of
// a curved drift too, falls from 0 Hz; a period's peaks at its frequency), stands out as the fast
// band's does and is not the input's; 0 when none.
double slow_peak(std::span<const double> time, std::span<const double> r, std::span<const double> p,
                 double dt, const Samples& train) {
  const Spectrum s = amplitude_spectrum(r, dt);
  const Spectrum input = amplitude_spectrum(p, dt);
  const double duration = time.empty() ? 0.0 : time.back() - time.front();
  if (s.frequency.size() < 8 || !(duration > 0.0)) return 0.0;
  const double lowest = kMinPeriodicCycles / duration;
  std::size_t peak = 0;
  for (std::size_t k = 1; k < s.frequency.size() && s.frequency[k] < kMinPeriodicFrequency; ++k)
    if (s.frequency[k] >= lowest && s.amplitude[k] > s.amplitude[peak]) peak = k;
  if (peak == 0) return 0.0;
  for (std::size_t k = 1; k < peak; ++k)
    if (s.amplitude[k] >= s.amplitude[peak]) return 0.0;
  const auto amplitude = [&](std::size_t k) { return s.amplitude[k]; };
  if (!stands_out(s.frequency, peak, amplitude) || !not_the_inputs(s, input, peak)) return 0.0;
  return fitted_frequency(time, r, s, peak, train);
}

// A static map: bins at quantiles of the train samples' x, each the mean residual at the mean x
// of its bin; linear between them and along the end segments beyond them.
class StaticMap {
 public:
  // `offset`: what every bin's mean is taken from (the whole train set's mean residual: a map of
  // a subset keeps what sets it apart).
  StaticMap(std::span<const double> x, std::span<const double> r, const Samples& train,
            double offset) {
    Samples sorted = train;
    std::sort(sorted.begin(), sorted.end(),
              [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
    const double m = offset;
    for (std::size_t b = 0; b < kMapBins; ++b) {
      const std::size_t from = b * sorted.size() / kMapBins,
                        to = (b + 1) * sorted.size() / kMapBins;
      if (to <= from) continue;
      double sx = 0.0, sr = 0.0;
      for (std::size_t i = from; i < to; ++i) {
        sx += x[sorted[i]];
        sr += r[sorted[i]] - m;
      }
      const auto count = static_cast<double>(to - from);
      if (!centres_.empty() && sx / count <= centres_.back()) continue;  // repeated values
      centres_.push_back(sx / count);
      values_.push_back(sr / count);
    }
  }
  double operator()(double x) const {
    if (centres_.empty()) return 0.0;
    if (centres_.size() == 1) return values_.front();
    const auto i = std::clamp<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(centres_.begin(), centres_.end(), x) -
                                 centres_.begin()),
        1, centres_.size() - 1);
    const double s = (x - centres_[i - 1]) / (centres_[i] - centres_[i - 1]);
    return values_[i - 1] + s * (values_[i] - values_[i - 1]);
  }

 private:
  std::vector<double> centres_, values_;
};

std::vector<double> evaluate(const StaticMap& map, std::span<const double> x) {
  std::vector<double> out(x.size());
  for (std::size_t j = 0; j < x.size(); ++j) out[j] = map(x[j]);
  return out;
}

// The sign of dp/dt at every sample (central differences).
std::vector<bool> rising(std::span<const double> p) {
  std::vector<bool> out(p.size(), true);
  for (std::size_t j = 0; j < p.size(); ++j) {
    const std::size_t a = j > 0 ? j - 1 : j, b = j + 1 < p.size() ? j + 1 : j;
    out[j] = p[b] >= p[a];
  }
  return out;
}

Samples where(const Samples& from, const std::vector<bool>& rise, bool value) {
  Samples out;
  for (std::size_t j : from)
    if (rise[j] == value) out.push_back(j);
  return out;
}

// The percentile q (0..1) of |p| over `at`.
double abs_percentile(std::span<const double> p, const Samples& at, double q) {
  std::vector<double> a;
  for (std::size_t j : at) a.push_back(std::abs(p[j]));
  if (a.empty()) return 0.0;
  const auto i = static_cast<std::size_t>(q * static_cast<double>(a.size() - 1));
  std::nth_element(a.begin(), a.begin() + static_cast<long>(i), a.end());
  return a[i];
}

// sum r p / sum p^2 over the samples of `at` with p on the side `positive`.
double side_gain(std::span<const double> r, std::span<const double> p, const Samples& at,
                 bool positive) {
  double rp = 0.0, pp = 0.0;
  for (std::size_t j : at)
    if ((p[j] > 0.0) == positive) {
      rp += r[j] * p[j];
      pp += p[j] * p[j];
    }
  return pp > 0.0 ? rp / pp : 0.0;
}

// The power, over the held-out samples, of the map's odd part less its line through 0 (a gain,
// which the model holds) and of its even part less its mean (a constant is no signature).
std::pair<double, double> odd_even_power(const StaticMap& map, std::span<const double> p,
                                         const Samples& heldout) {
  std::vector<double> even(p.size(), 0.0), odd(p.size(), 0.0);
  double op = 0.0, pp = 0.0;
  for (std::size_t j : heldout) {
    even[j] = 0.5 * (map(p[j]) + map(-p[j]));
    odd[j] = 0.5 * (map(p[j]) - map(-p[j]));
    op += odd[j] * p[j];
    pp += p[j] * p[j];
  }
  const double gain = pp > 0.0 ? op / pp : 0.0;
  double curved = 0.0;
  for (std::size_t j : heldout) curved += (odd[j] - gain * p[j]) * (odd[j] - gain * p[j]);
  return {curved, spread_over(even, heldout)};
}

// r on the train samples less their mean, or their line through time when `detrended` (0 on the
// held-out samples).
std::vector<double> train_part(std::span<const double> time, std::span<const double> r,
                               const Samples& train, bool detrended) {
  const double mt = mean_over(time, train), mr = mean_over(r, train);
  double tt = 0.0, tr = 0.0;
  for (std::size_t j : train) {
    tt += (time[j] - mt) * (time[j] - mt);
    tr += (time[j] - mt) * (r[j] - mr);
  }
  const double slope = detrended && tt > 0.0 ? tr / tt : 0.0;
  std::vector<double> out(r.size(), 0.0);
  for (std::size_t j : train) out[j] = r[j] - mr - slope * (time[j] - mt);
  return out;
}

// The sinusoid at `f` (> 0) fitted on the train samples, accepted where it explains
// kMinExplained of r's held-out variance: then subtracted from r.
bool accept_periodic(std::span<const double> time, double f, std::vector<double>& r,
                     const Halves& h, ResidualDescription& out) {
  if (f <= 0.0) return false;
  double amplitude = 0.0;
  const std::vector<double> d = sinusoid(time, r, f, h.train, amplitude);
  const double e = explained(r, d, h.heldout);
  if (e < kMinExplained) return false;
  out.periodic = PeriodicSignature{f, amplitude, e};
  for (std::size_t j = 0; j < r.size(); ++j) {
    r[j] -= d[j];
    out.described[j] += d[j];
  }
  return true;
}

// The periodic test on r, the fast band first, then the slow one; its part is subtracted from r
// when accepted.
void periodic_test(std::span<const double> time, std::span<const double> p, std::vector<double>& r,
                   double dt, const Halves& h, ResidualDescription& out) {
  if (accept_periodic(time, spectral_peak(time, train_part(time, r, h.train, false), p, dt), r, h,
                      out))
    return;
  accept_periodic(time, slow_peak(time, train_part(time, r, h.train, true), p, dt, h.train), r, h,
                  out);
}

// The rate of p at every sample (central differences, unit/s).
std::vector<double> rate_of(std::span<const double> p, double dt) {
  std::vector<double> out(p.size(), 0.0);
  for (std::size_t j = 0; j < p.size(); ++j) {
    const std::size_t a = j > 0 ? j - 1 : j, b = j + 1 < p.size() ? j + 1 : j;
    if (b > a) out[j] = (p[b] - p[a]) / (static_cast<double>(b - a) * dt);
  }
  return out;
}

// The map over x (p or its rate) read as a signature: its even part (less its mean) a
// dependence on x's sign, "direction", with g+ - g-; its odd part less its line through 0 one on
// x's amplitude, "amplitude", with M_odd(x_98) / x_98 - M_odd(x_50) / x_50. Both in r / x: a
// ratio for p, seconds (the measured's lead on the model) for its rate.
void read_map(const StaticMap& map, std::span<const double> x, std::span<const double> r,
              const Halves& h, double e, bool of_rate, ResidualDescription& out) {
  const auto [curved, even] = odd_even_power(map, x, h.heldout);
  if (even >= curved) {
    const double g = side_gain(r, x, h.train, true) - side_gain(r, x, h.train, false);
    out.direction =
        DirectionSignature{e, of_rate ? 0.0 : 100.0 * g, 0.0, of_rate, of_rate ? g : 0.0};
    return;
  }
  const double median = abs_percentile(x, h.train, 0.5), top = abs_percentile(x, h.train, 0.98);
  const auto odd_ratio = [&](double v) { return v > 0.0 ? 0.5 * (map(v) - map(-v)) / v : 0.0; };
  const double change = odd_ratio(top) - odd_ratio(median);
  out.amplitude =
      AmplitudeSignature{e, of_rate ? 0.0 : 100.0 * change, top, of_rate, of_rate ? change : 0.0};
}

// The static maps on r against p, per direction of p and against p's rate; the one accepted (the
// one explaining most held out) is subtracted from r.
void map_test(std::span<const double> p, std::vector<double>& r, double dt, const Halves& h,
              ResidualDescription& out) {
  const double offset = mean_over(r, h.train);
  const StaticMap map(p, r, h.train, offset);
  std::vector<double> d = evaluate(map, p);
  const double e = explained(r, d, h.heldout);
  const std::vector<bool> rise = rising(p);
  const StaticMap up(p, r, where(h.train, rise, true), offset),
      down(p, r, where(h.train, rise, false), offset);
  std::vector<double> split(p.size());
  double width = 0.0;
  for (std::size_t j = 0; j < p.size(); ++j) split[j] = rise[j] ? up(p[j]) : down(p[j]);
  for (std::size_t j : h.heldout) width += (up(p[j]) - down(p[j])) * (up(p[j]) - down(p[j]));
  const double e_split = explained(r, split, h.heldout);
  const bool hysteretic = e_split - std::max(e, 0.0) >= kMinExplained;
  const std::vector<double> v = rate_of(p, dt);
  const StaticMap rate_map(v, r, h.train, offset);
  const std::vector<double> d_rate = evaluate(rate_map, v);
  const double e_rate = explained(r, d_rate, h.heldout);
  // A line over the rate is a lag the fit holds: the rate's map counts only for its bends and
  // its sides (the power of its odd part less the line and of its even part).
  const auto [rate_curved, rate_even] = odd_even_power(rate_map, v, h.heldout);
  const bool by_rate = e_rate >= kMinExplained &&
                       e_rate > std::max(e, hysteretic ? e_split : 0.0) &&
                       rate_curved + rate_even >= kMinExplained * spread_over(r, h.heldout);
  if (e < kMinExplained && !hysteretic && !by_rate) return;
  if (by_rate) {
    read_map(rate_map, v, r, h, e_rate, true, out);
    d = d_rate;
  } else if (hysteretic) {
    const double g_up = side_gain(r, p, h.train, true), g_down = side_gain(r, p, h.train, false);
    out.direction = DirectionSignature{e_split, 100.0 * (g_up - g_down),
                                       std::sqrt(width / static_cast<double>(h.heldout.size()))};
    d = split;
  } else {
    read_map(map, p, r, h, e, false, out);
  }
  for (std::size_t j = 0; j < r.size(); ++j) {
    r[j] -= d[j];
    out.described[j] += d[j];
  }
}

// Per window: rho = sum r p / sum p^2.
std::vector<double> window_gains(std::span<const double> r, std::span<const double> p,
                                 const Halves& h) {
  std::vector<double> rp(kDescriptionWindows, 0.0), pp(kDescriptionWindows, 0.0);
  for (std::size_t j = 0; j < r.size(); ++j) {
    rp[h.window[j]] += r[j] * p[j];
    pp[h.window[j]] += p[j] * p[j];
  }
  std::vector<double> out(kDescriptionWindows, 0.0);
  for (std::size_t w = 0; w < out.size(); ++w) out[w] = pp[w] > 0.0 ? rp[w] / pp[w] : 0.0;
  return out;
}

// The line through (w, rho_w): its slope per window and that slope's standard error.
std::pair<double, double> trend_line(const std::vector<double>& rho) {
  const auto n = static_cast<double>(rho.size());
  double sw = 0.0, sr = 0.0;
  for (std::size_t w = 0; w < rho.size(); ++w) {
    sw += static_cast<double>(w);
    sr += rho[w];
  }
  const double mw = sw / n, mr = sr / n;
  double sww = 0.0, swr = 0.0;
  for (std::size_t w = 0; w < rho.size(); ++w) {
    sww += (static_cast<double>(w) - mw) * (static_cast<double>(w) - mw);
    swr += (static_cast<double>(w) - mw) * (rho[w] - mr);
  }
  const double slope = swr / sww;
  double sse = 0.0;
  for (std::size_t w = 0; w < rho.size(); ++w) {
    const double e = rho[w] - mr - slope * (static_cast<double>(w) - mw);
    sse += e * e;
  }
  return {slope, std::sqrt(sse / (n - 2.0) / sww)};
}

// Whether the windows' rho follows their size (the RMS of p in each) at least as closely as it
// follows time: the sum of squares each line leaves.
bool follows_size_more_than_time(std::span<const double> p, const Halves& h,
                                 const std::vector<double>& rho) {
  std::vector<double> squares(kDescriptionWindows, 0.0), counts(kDescriptionWindows, 0.0);
  for (std::size_t j = 0; j < p.size(); ++j) {
    squares[h.window[j]] += p[j] * p[j];
    counts[h.window[j]] += 1.0;
  }
  const auto left_by_line = [&](const std::vector<double>& x) {
    const auto n = static_cast<double>(rho.size());
    double mx = 0.0, mr = 0.0;
    for (std::size_t w = 0; w < rho.size(); ++w) {
      mx += x[w] / n;
      mr += rho[w] / n;
    }
    double sxx = 0.0, sxr = 0.0, srr = 0.0;
    for (std::size_t w = 0; w < rho.size(); ++w) {
      sxx += (x[w] - mx) * (x[w] - mx);
      sxr += (x[w] - mx) * (rho[w] - mr);
      srr += (rho[w] - mr) * (rho[w] - mr);
    }
    return sxx > 0.0 ? srr - sxr * sxr / sxx : srr;
  };
  std::vector<double> size(kDescriptionWindows), place(kDescriptionWindows);
  for (std::size_t w = 0; w < size.size(); ++w) {
    size[w] = counts[w] > 0.0 ? std::sqrt(squares[w] / counts[w]) : 0.0;
    place[w] = static_cast<double>(w);
  }
  return left_by_line(size) <= left_by_line(place);
}

// The time-varying test on r: rho tracked in windows, against p (or, of_rate, p's rate, where
// rho follows time more closely than the rate's size: a term that grows unlike the rate is the
// rate map's amplitude, not a change over the record).
void trend_test(std::span<const double> time, std::span<const double> p, std::vector<double>& r,
                const Halves& h, ResidualDescription& out, bool of_rate = false) {
  const std::vector<double> rho = window_gains(r, p, h);
  std::vector<double> d(r.size(), 0.0);
  const std::size_t n = r.size();
  for (std::size_t j = 0; j < n; ++j) {
    // Linear between the even (train) windows' centres, at the sample's place in the record.
    const double place = (static_cast<double>(j) + 0.5) * kDescriptionWindows / n - 0.5;
    const double below = std::clamp(2.0 * std::floor(place / 2.0), 0.0,
                                    static_cast<double>(kDescriptionWindows - 2));
    const double s = std::clamp((place - below) / 2.0, 0.0, 1.0);
    const auto b = static_cast<std::size_t>(below);
    const double above = b + 2 < kDescriptionWindows ? rho[b + 2] : rho[b];
    d[j] = (rho[b] + s * (above - rho[b])) * p[j];
  }
  const double e = explained(r, d, h.heldout);
  const auto [slope, error] = trend_line(rho);
  if (e < kMinExplained || !(std::abs(slope) >= kTrendSigmas * error)) return;
  if (of_rate && follows_size_more_than_time(p, h, rho)) return;
  std::vector<double> centres(kDescriptionWindows);
  for (std::size_t w = 0; w < centres.size(); ++w)
    centres[w] = time[std::min(n - 1, (2 * w + 1) * n / (2 * kDescriptionWindows))];
  const ShapeFit shape = fit_shape(centres, rho);
  out.time_varying =
      TrendSignature{e, of_rate ? 0.0 : 100.0 * (shape.end - shape.start), shape, of_rate};
  for (std::size_t j = 0; j < n; ++j) {
    r[j] -= d[j];
    out.described[j] += d[j];
  }
}

// The map and the trend in both orders; the order that leaves less held out is kept (a residual
// of the input's amplitude on a record whose amplitude changes over time shows in both).
void input_tests(std::span<const double> time, std::span<const double> p, std::vector<double>& r,
                 double dt, const Halves& h, ResidualDescription& out) {
  ResidualDescription map_first = out, trend_first = out;
  std::vector<double> r_map = r, r_trend = r;
  map_test(p, r_map, dt, h, map_first);
  trend_test(time, p, r_map, h, map_first);
  trend_test(time, p, r_trend, h, trend_first);
  map_test(p, r_trend, dt, h, trend_first);
  const bool map_wins = spread_over(r_map, h.heldout) <= spread_over(r_trend, h.heldout);
  out = map_wins ? std::move(map_first) : std::move(trend_first);
  r = map_wins ? std::move(r_map) : std::move(r_trend);
  if (!out.time_varying) trend_test(time, rate_of(p, dt), r, h, out, true);
}

}  // namespace

std::vector<double> minus(std::span<const double> a, std::span<const double> b) {
  std::vector<double> out(a.size());
  for (std::size_t j = 0; j < a.size(); ++j) out[j] = a[j] - b[j];
  return out;
}

std::vector<std::string> ResidualDescription::kinds() const {
  std::vector<std::string> out;
  if (periodic) out.push_back("periodic");
  if (amplitude) out.push_back("amplitude");
  if (direction) out.push_back("direction");
  if (time_varying) out.push_back("time_varying");
  return out;
}

ResidualDescription describe_residual(std::span<const double> time,
                                      std::span<const double> residual,
                                      std::span<const double> prediction, double dt) {
  ResidualDescription out;
  const Halves h = alternate_windows(residual.size());
  out.described.assign(residual.size(), 0.0);
  std::vector<double> left(residual.begin(), residual.end());
  input_tests(time, prediction, left, dt, h, out);
  periodic_test(time, prediction, left, dt, h, out);
  Samples all(residual.size());
  for (std::size_t j = 0; j < all.size(); ++j) all[j] = j;
  out.residual_rms = std::sqrt(spread_over(residual, all) / static_cast<double>(all.size()));
  out.explained = explained(residual, out.described, h.heldout);
  out.heldout_rms = std::sqrt(spread_over(minus(residual, out.described), h.heldout) /
                              static_cast<double>(h.heldout.size()));
  out.described_rms = std::sqrt(spread_over(out.described, all) / static_cast<double>(all.size()));
  // What a re-run puts back holds the residual's mean too: the model left it, whatever holds it.
  if (out.any())
    for (double& d : out.described) d += mean_over(residual, h.train);
  return out;
}

double heldout_rms(std::span<const double> residual) {
  const Halves h = alternate_windows(residual.size());
  return std::sqrt(spread_over(residual, h.heldout) / static_cast<double>(h.heldout.size()));
}

}  // namespace rths::identify
