#include "identify/residual/locate.h"

#include <algorithm>
#include <cmath>

#include "identify/model/spectra.h"

namespace rths::identify {

std::vector<ResidualWindow> residual_windows(std::span<const double> time,
                                             std::span<const double> residual) {
  const std::size_t n = residual.size(), w = kFloorWindows;
  std::vector<double> power(w, 0.0);
  double total = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    power[std::min(w - 1, j * w / n)] += residual[j] * residual[j];
    total += residual[j] * residual[j];
  }
  std::vector<ResidualWindow> out;
  if (!(total > 0.0)) return out;
  const double least = kWindowOverUniform / static_cast<double>(w);
  for (std::size_t i = 0; i < w; ++i) {
    if (power[i] / total < least) continue;
    const double start = time[i * n / w], end = time[std::min(n - 1, (i + 1) * n / w)];
    if (!out.empty() && power[i - 1] / total >= least) {
      out.back().end = end;
      out.back().share += power[i] / total;
    } else {
      out.push_back({start, end, power[i] / total});
    }
  }
  std::sort(out.begin(), out.end(),
            [](const ResidualWindow& a, const ResidualWindow& b) { return a.share > b.share; });
  if (out.size() > kMaxWindows) out.resize(kMaxWindows);
  return out;
}

ResidualBand residual_band(std::span<const double> r, double dt) {
  ResidualBand out;
  const Spectrum s = amplitude_spectrum(r, dt);
  double total = 0.0, peak = 0.0;
  for (std::size_t k = 1; k < s.amplitude.size(); ++k) {
    const double power = s.amplitude[k] * s.amplitude[k];
    total += power;
    if (power > peak) {
      peak = power;
      out.peak_hz = s.frequency[k];
    }
  }
  if (!(total > 0.0)) return out;
  double cumulative = 0.0;
  bool low = false;
  for (std::size_t k = 1; k < s.amplitude.size(); ++k) {
    cumulative += s.amplitude[k] * s.amplitude[k];
    if (!low && cumulative >= 0.1 * total) {
      out.low_hz = s.frequency[k];
      low = true;
    }
    if (cumulative >= 0.9 * total) {
      out.high_hz = s.frequency[k];
      return out;
    }
  }
  return out;
}

double rms_above(std::span<const double> r, double dt, double cutoff) {
  if (!(cutoff > 0.0) || r.size() < 16) return 0.0;
  const Spectrum s = amplitude_spectrum(r, dt);
  double total = 0.0, above = 0.0;
  for (std::size_t k = 1; k < s.amplitude.size(); ++k) {
    const double power = s.amplitude[k] * s.amplitude[k];
    total += power;
    if (s.frequency[k] > cutoff) above += power;
  }
  double mean_square = 0.0;
  for (double x : r) mean_square += x * x / static_cast<double>(r.size());
  return total > 0.0 ? std::sqrt(mean_square * above / total) : 0.0;
}

double correlation_ratio(std::span<const double> x, std::span<const double> r) {
  if (x.size() != r.size() || r.size() < 2 * kRelationBins) return 0.0;
  std::vector<std::size_t> order(r.size());
  for (std::size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
  double mean = 0.0, total = 0.0, left = 0.0;
  for (double v : r) mean += v / static_cast<double>(r.size());
  for (std::size_t bin = 0; bin < kRelationBins; ++bin) {
    const std::size_t from = bin * r.size() / kRelationBins,
                      to = (bin + 1) * r.size() / kRelationBins;
    double bin_mean = 0.0;
    for (std::size_t k = from; k < to; ++k)
      bin_mean += r[order[k]] / static_cast<double>(to - from);
    for (std::size_t k = from; k < to; ++k) {
      total += (r[order[k]] - mean) * (r[order[k]] - mean);
      left += (r[order[k]] - bin_mean) * (r[order[k]] - bin_mean);
    }
  }
  return total > 0.0 ? 1.0 - left / total : 0.0;
}

}  // namespace rths::identify
