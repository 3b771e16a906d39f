#include "identify/run/network_path.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "identify/model/data.h"
#include "identify/model/model.h"
#include "identify/residual/robust.h"

namespace rths::identify {
namespace {

double rms_about(const std::vector<double>& x, const std::vector<double>& model,
                 const std::vector<std::size_t>& samples) {
  double sum = 0.0;
  for (std::size_t i : samples) sum += (x[i] - model[i]) * (x[i] - model[i]);
  return samples.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(samples.size()));
}

std::string ms(double seconds) {
  std::ostringstream out;
  out.precision(3);
  out << seconds * 1e3 << " ms";
  return out.str();
}

// Normalised time of each answer over the run, in [-1/2, 1/2] (model.h drift_profile).
std::vector<double> normalised_time(const std::vector<double>& time) {
  const double mid = 0.5 * (time.front() + time.back());
  const double span = std::max(time.back() - time.front(), 1e-12);
  std::vector<double> s;
  for (double t : time) s.push_back((t - mid) / span);
  return s;
}

// bias + D(s; c) fitted by least squares on `fit_on`; evaluated at every answer.
std::vector<double> drift_model(const std::vector<double>& x, const std::vector<double>& s,
                                const std::vector<std::size_t>& fit_on) {
  const auto rows = static_cast<Eigen::Index>(fit_on.size());
  const auto cols = static_cast<Eigen::Index>(kDriftTerms + 2);
  Eigen::MatrixXd a(rows, cols);
  Eigen::VectorXd b(rows);
  std::vector<double> unit(kDriftTerms, 0.0);
  const auto basis = [&](double si, std::size_t k) {
    std::fill(unit.begin(), unit.end(), 0.0);
    unit[k] = 1.0;
    return drift_profile(unit, si);
  };
  for (Eigen::Index r = 0; r < rows; ++r) {
    const std::size_t i = fit_on[static_cast<std::size_t>(r)];
    a(r, 0) = 1.0;
    a(r, 1) = s[i];
    for (std::size_t k = 0; k < kDriftTerms; ++k)
      a(r, static_cast<Eigen::Index>(k + 2)) = basis(s[i], k);
    b(r) = x[i];
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  std::vector<double> coefficients(c.data() + 2, c.data() + cols);
  std::vector<double> model;
  for (double si : s) model.push_back(c(0) + c(1) * si + drift_profile(coefficients, si));
  return model;
}

std::vector<std::size_t> spike_indices(const std::vector<double>& x, double threshold,
                                       const std::vector<std::size_t>& among) {
  std::vector<std::size_t> out;
  for (std::size_t i : among) {
    if (x[i] > threshold) out.push_back(i);
  }
  return out;
}

// The starts of the bursts of spikes at `times` (a spike within 3 steps of the one before is in
// its burst: a stall longer than 3 steps is one burst, not several).
std::vector<double> burst_starts(const std::vector<double>& times, double dt) {
  std::vector<double> starts;
  double last = -1e300;
  for (double t : times) {
    if (t - last > 3.0 * dt) starts.push_back(t);
    last = t;
  }
  return starts;
}

// Whether t lies on the grid t0 + k period (within 3 steps or 2 % of the period).
bool on_grid(double t, double t0, double period, double dt) {
  const double off = t - t0 - std::round((t - t0) / period) * period;
  return std::abs(off) <= std::max(3.0 * dt, 0.02 * period);
}

// The burst start that the most other starts lie on the grid of: the phase of the periodic
// spikes, not of a stray one.
double grid_origin(const std::vector<double>& starts, double period, double dt) {
  double best = starts.front();
  std::ptrdiff_t most = -1;
  for (double t0 : starts) {
    const auto n = std::count_if(starts.begin(), starts.end(),
                                 [&](double t) { return on_grid(t, t0, period, dt); });
    if (n > most) most = n, best = t0;
  }
  return best;
}

// Histogram of the spacings between every pair of burst starts up to half their span, in bins
// of 2 steps: periodic bursts pile up at their period (and its multiples), a busy host's stray
// ones spread evenly.
std::vector<int> spacing_histogram(const std::vector<double>& starts, double bin) {
  const double half = 0.5 * (starts.back() - starts.front());
  std::vector<int> count(static_cast<std::size_t>(half / bin) + 2, 0);
  for (std::size_t i = 0; i < starts.size(); ++i) {
    for (std::size_t j = i + 1; j < starts.size() && starts[j] - starts[i] <= half; ++j)
      ++count[static_cast<std::size_t>((starts[j] - starts[i]) / bin)];
  }
  return count;
}

// The spacing that the most pairs of burst starts share (two adjacent bins), when that count is
// at least 3 and stands 4 standard deviations above the histogram's mean; a whole fraction of it
// (1/5 .. 1/2) that holds at least half as many pairs instead (a peak at 2P is P's multiple);
// the mean spacing of its pairs. 0 when none stands out.
double peak_spacing(const std::vector<double>& starts, double dt) {
  const double bin = 2.0 * dt;
  const std::vector<int> count = spacing_histogram(starts, bin);
  const auto pair_count = [&](std::size_t b) { return count[b] + count[b + 1]; };
  const std::size_t first = 2;  // spacings of 4 steps or less are within one burst
  if (count.size() < first + 3) return 0.0;
  std::size_t peak = first;
  double mean = 0.0;
  for (std::size_t b = first; b + 1 < count.size(); ++b) {
    mean += pair_count(b) / static_cast<double>(count.size() - 1 - first);
    if (pair_count(b) > pair_count(peak)) peak = b;
  }
  if (pair_count(peak) < 3 || pair_count(peak) < mean + 4.0 * std::sqrt(mean)) return 0.0;
  for (std::size_t k = 5; k >= 2; --k) {
    const std::size_t b = peak / k;
    if (b <= first) continue;
    const std::size_t at = pair_count(b - 1) >= pair_count(b) ? b - 1 : b;
    if (2 * pair_count(at) >= pair_count(peak)) {
      peak = at;
      break;
    }
  }
  double sum = 0.0, n = 0.0;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    for (std::size_t j = i + 1; j < starts.size(); ++j) {
      const double d = starts[j] - starts[i];
      if (d >= static_cast<double>(peak) * bin && d < static_cast<double>(peak + 2) * bin)
        sum += d, n += 1.0;
    }
  }
  return sum / n;
}

struct SpikeGrid {
  double period = 0.0, origin = 0.0;  // s; period 0: the spikes do not recur
  std::size_t on = 0;                 // burst starts on the grid
};

// The grid origin + k period fitted by least squares to the burst starts on the grid of
// (grid_origin, period): a spacing measured among strays is off by a fraction of a step, which
// over the run's periods would slide the grid off the spikes.
SpikeGrid fitted_grid(const std::vector<double>& starts, double period, double dt) {
  SpikeGrid grid{period, grid_origin(starts, period, dt), 0};
  double sk = 0.0, st = 0.0, skk = 0.0, skt = 0.0;
  for (double t : starts) {
    if (!on_grid(t, grid.origin, period, dt)) continue;
    const double k = std::round((t - grid.origin) / period);
    sk += k, st += t, skk += k * k, skt += k * t, ++grid.on;
  }
  const double n = static_cast<double>(grid.on), denominator = n * skk - sk * sk;
  if (grid.on < 3 || denominator <= 0.0) return grid;
  grid.period = (n * skt - sk * st) / denominator;
  grid.origin = (st - grid.period * sk) / n;
  return grid;
}

// The spikes' grid (network_path.h): the peak spacing of their bursts' starts, fitted, kept when
// at least 3 starts and half the grid's slots over the run lie on it; period 0 otherwise.
SpikeGrid regular_grid(const std::vector<double>& times, double dt) {
  const std::vector<double> starts = burst_starts(times, dt);
  if (starts.size() < 3) return {};
  const double period = peak_spacing(starts, dt);
  if (period <= 0.0) return {};
  const SpikeGrid grid = fitted_grid(starts, period, dt);
  const double slots = (starts.back() - starts.front()) / grid.period;
  if (grid.period <= 0.0 || grid.on < 3 || static_cast<double>(grid.on) < 0.5 * slots) return {};
  return grid;
}

// Lost answers (network_path.h): per gap of g steps between two answers taken in a row, of
// which the coordinator's count says r more were received (superseded within a step), g - r are
// lost, taken as one burst (a superseded answer arrived a step or so late, so it lies at the
// gap's edge, next to the answer that superseded it or the one before the gap).
// Without the count (0), every gap is lost. Late: answers carried more than one step after the
// usual.
void count_lost_and_late(const LinkAnswers& a, double dt, NetworkPath& out) {
  const bool counted = a.answers.size() == a.answered_step.size();
  for (std::size_t i = 1; i < a.answered_step.size(); ++i) {
    const std::int64_t gap = a.answered_step[i] - a.answered_step[i - 1] - 1;
    if (gap <= 0) continue;
    std::int64_t received = 0;
    if (counted && a.answers[i - 1] > 0 && a.answers[i] > a.answers[i - 1])
      received = std::min(gap, a.answers[i] - a.answers[i - 1] - 1);
    const std::int64_t lost = gap - received;
    out.superseded += static_cast<std::size_t>(received);
    out.lost += static_cast<std::size_t>(lost);
    out.longest_burst = std::max(out.longest_burst, static_cast<std::size_t>(lost));
  }
  std::vector<double> carried;
  for (std::size_t i = 0; i < a.time.size(); ++i) {
    carried.push_back(std::round(a.time[i] / dt) - static_cast<double>(a.answered_step[i]));
  }
  const double usual = median_of(carried);
  for (double c : carried) out.late += c > usual + 1.0 ? 1 : 0;
}

// The named effects judged by counting (network_path.h): lost answers and the injection.
void counted_effects(NetworkPath& out) {
  const double expected_burst_probability =
      static_cast<double>(out.answers) *
      std::pow(out.declared.loss, static_cast<double>(out.longest_burst));
  if (out.lost > 0 && !out.declared.drops &&
      (out.declared.loss == 0.0 || (out.longest_burst >= 3 && expected_burst_probability < 1e-3))) {
    out.effects.push_back({"lost answers",
                           std::to_string(out.lost) + " lost, longest burst " +
                               std::to_string(out.longest_burst) + " consecutive (declared loss " +
                               std::to_string(out.declared.loss) + ")",
                           0.0, 0.0, 0.0});
  }
  const double difference = out.injected_mean - out.declared.round_trip;
  if (std::abs(difference) > std::max(1e-4, 0.05 * out.declared.round_trip)) {
    out.effects.push_back({"injection",
                           "the node injected " + ms(out.injected_mean) +
                               " per round trip, the config declares " +
                               ms(out.declared.round_trip),
                           0.0, 0.0, 0.0});
  }
}

// Periodic spikes predicted from the training answers: at times t0 + k P, lasting as long as
// the median run of training spikes on that grid, of their median height above `base` (the
// stray spikes off the grid are left out of both, and a stray next to a periodic spike lengthens
// one run only).
std::vector<double> spike_model(const std::vector<double>& x, const std::vector<double>& time,
                                const std::vector<double>& base,
                                const std::vector<std::size_t>& train_spikes, const SpikeGrid& grid,
                                double dt) {
  std::vector<double> heights;
  const double t0 = grid.origin, period = grid.period;
  std::vector<double> widths;  // of each run of spikes on the grid
  double last = -1e300;
  for (std::size_t i : train_spikes) {
    if (!on_grid(time[i], t0, period, dt)) continue;  // a stray: neither height nor width
    heights.push_back(x[i] - base[i]);
    if (time[i] - last > 3.0 * dt) widths.push_back(0.0);
    widths.back() += time[i] - std::max(last, time[i] - dt);
    last = time[i];
  }
  const double height = median_of(heights), width = std::max(dt, median_of(widths));
  std::vector<double> model = base;
  for (std::size_t i = 0; i < x.size(); ++i) {
    double phase = std::fmod(time[i] - t0 + 1e3 * period, period);
    if (phase > period - 0.5 * dt) phase -= period;  // a rounding short of a whole period
    if (phase >= -0.5 * dt && phase < width - 0.5 * dt) model[i] += height;
  }
  return model;
}

// A candidate pays when the held-out RMS falls by at least 20 % and by more than kMinEffect.
bool pays(double before, double after) {
  return after <= 0.8 * before && before - after > kMinEffect;
}

std::vector<std::size_t> without(const std::vector<std::size_t>& samples,
                                 const std::vector<double>& x, double threshold) {
  std::vector<std::size_t> out;
  for (std::size_t i : samples) {
    if (x[i] <= threshold) out.push_back(i);
  }
  return out;
}

// The spikes above `threshold` (count, median height above the bias) and their period
// (network_path.h): found at the level, of `threshold` and the spikes' height quantiles 50, 75
// and 90 %, whose grid covers the most of its slots over the run, at most all (ties: the grid
// with the most starts on it) (a periodic spike above most of
// a busy host's stray ones recurs at a level they rarely reach, and there fills its grid while a
// grid among strays is half empty). Returns that level (`threshold` when none recurs).
double recurring_spikes(const std::vector<double>& x, const std::vector<double>& time,
                        double threshold, double dt, NetworkPath& out) {
  std::vector<std::size_t> all(x.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  const auto spikes = spike_indices(x, threshold, all);
  std::vector<double> levels{threshold}, heights;
  for (std::size_t i : spikes) heights.push_back(x[i]);
  std::sort(heights.begin(), heights.end());
  for (double q : {0.5, 0.75, 0.9}) {
    if (!heights.empty())
      levels.push_back(heights[static_cast<std::size_t>(q * static_cast<double>(heights.size()))]);
  }
  out.spikes = spikes.size();
  out.spike_height = heights.empty() ? 0.0 : median_of(heights) - out.bias;
  double chosen = threshold, best = 0.0;
  std::size_t best_on = 0;
  for (double level : levels) {
    std::vector<double> times;
    for (std::size_t i : spikes) {
      if (x[i] >= level) times.push_back(time[i]);
    }
    const SpikeGrid grid = regular_grid(times, dt);
    // A full grid covers 1: three starts on a coarse grid (a multiple of the period, among the
    // highest spikes) cover no more than twenty on the period's own, and the more starts win.
    const double coverage =
        std::min(1.0, static_cast<double>(grid.on) * grid.period / (time.back() - time.front()));
    if (grid.period > 0.0 &&
        (coverage > best + 1e-9 || (coverage > best - 1e-9 && grid.on > best_on))) {
      best = coverage, best_on = grid.on, chosen = level;
      out.spike_period = grid.period;
    }
  }
  return chosen;
}

// The fitted candidates (network_path.h): drifting delay, then periodic spikes on top of it.
void fit_effects(const LinkAnswers& a, const std::vector<double>& x, double dt, NetworkPath& out) {
  const Split split = holdout_split(x.size(), 0.3, HoldoutMode::kBlocks, 10, 5);
  const double threshold = out.bias + std::max(6.0 * out.jitter, kMinSpike);
  const double level = recurring_spikes(x, a.time, threshold, dt, out);
  const auto train = without(split.train, x, threshold);
  const auto heldout = without(split.heldout, x, threshold);
  std::vector<double> train_x;
  for (std::size_t i : train) train_x.push_back(x[i]);
  std::vector<double> base(x.size(), median_of(train_x));
  out.heldout_declared = rms_about(x, base, split.heldout);
  const std::vector<double> drift = drift_model(x, normalised_time(a.time), train);
  const auto [low, high] = std::minmax_element(drift.begin(), drift.end());
  out.drift_range = *high - *low;
  const double before = rms_about(x, base, heldout), after = rms_about(x, drift, heldout);
  if (pays(before, after)) {
    if (!out.declared.drift)
      out.effects.push_back({"drifting delay",
                             "the excess lag moves over " + ms(out.drift_range) + " in the run",
                             before, after, 0.0});
    base = drift;
  }
  out.model = base;
  const auto train_spikes = spike_indices(x, level, split.train);
  if (out.spike_period > 0.0 && train_spikes.size() >= 2) {
    std::vector<double> train_times;
    for (std::size_t i : train_spikes) train_times.push_back(a.time[i]);
    const SpikeGrid grid = fitted_grid(burst_starts(train_times, dt), out.spike_period, dt);
    const auto model = spike_model(x, a.time, base, train_spikes, grid, dt);
    // Judged without the held-out spikes off the model's slots: strays that neither model
    // explains, and whose size would only dilute the comparison.
    std::vector<std::size_t> judged;
    for (std::size_t i : split.heldout) {
      if (x[i] <= threshold || model[i] != base[i]) judged.push_back(i);
    }
    const double spikes_before = rms_about(x, base, judged);
    const double spikes_after = rms_about(x, model, judged);
    if (pays(spikes_before, spikes_after)) {
      if (!out.declared.spikes)
        out.effects.push_back({"periodic spikes",
                               std::to_string(out.spikes) + " spikes of " + ms(out.spike_height) +
                                   " every " + ms(out.spike_period),
                               spikes_before, spikes_after, 0.0});
      out.model = model;
    }
  }
  double removed = 0.0;
  for (const auto& e : out.effects) removed += e.heldout_before - e.heldout_after;
  for (auto& e : out.effects)
    e.share = removed > 0.0 ? (e.heldout_before - e.heldout_after) / removed : 0.0;
}

}  // namespace

NetworkPath identify_network_path(const LinkAnswers& a, const DeclaredLink& declared, double dt) {
  const std::size_t n = a.round_trip.size();
  if (n < 20) {
    throw std::invalid_argument("link to node " + std::to_string(a.node_id) + ": " +
                                std::to_string(n) + " answers, at least 20 are needed");
  }
  NetworkPath out;
  out.node_id = a.node_id;
  out.answers = n;
  out.declared = declared;
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = a.round_trip[i] - a.injected[i];
  out.bias = median_of(x);
  out.jitter = robust_sigma(x, out.bias);
  for (double q : a.injected) out.injected_mean += q / static_cast<double>(n);
  count_lost_and_late(a, dt, out);
  fit_effects(a, x, dt, out);
  counted_effects(out);
  out.time = a.time;
  out.round_trip = a.round_trip;
  out.injected = a.injected;
  for (std::size_t i = 0; i < n; ++i) out.model[i] += a.injected[i];
  return out;
}

}  // namespace rths::identify
