#include "identify/residual/events.h"

#include "identify/residual/robust.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace rths::identify {
namespace {

double mad_of(const std::vector<double>& x) { return robust_sigma(x, median_of(x)); }

// The running median of r over kMedianSpan samples centred on each, fewer towards the ends (a
// one-sided span would read a slope as a spike).
std::vector<double> running_median(const std::vector<double>& r) {
  std::vector<double> out(r.size()), span;
  const std::size_t half = kMedianSpan / 2;
  for (std::size_t j = 0; j < r.size(); ++j) {
    const std::size_t reach = std::min({half, j, r.size() - 1 - j});
    const std::size_t from = j - reach, to = j + reach + 1;
    span.assign(r.begin() + static_cast<std::ptrdiff_t>(from),
                r.begin() + static_cast<std::ptrdiff_t>(to));
    out[j] = median_of(span);
  }
  return out;
}

struct Search {
  std::span<const double> time, reading, prediction;
  std::vector<double> r;  // the residual, cleaned of held runs and spikes as they are found
  double total = 0.0;     // sum r^2 over the record, before cleaning
  double sigma = 0.0, dt = 0.0;
  std::vector<ResidualEvent> events;
};

void find_held(Search& s) {
  const std::size_t n = s.r.size();
  for (std::size_t from = 0; from < n;) {
    std::size_t to = from + 1;
    while (to < n && s.reading[to] == s.reading[from]) ++to;
    if (to - from >= kMinHeldSamples) {
      double power = 0.0;
      for (std::size_t j = from; j < to; ++j) power += s.r[j] * s.r[j];
      const double rms = std::sqrt(power / static_cast<double>(to - from));
      if (rms > kEventFactor * s.sigma && power > 0.0) {
        s.events.push_back(
            {EventKind::kHeldSample, s.time[from], s.time[to - 1], power / s.total, rms});
        for (std::size_t j = from; j < to; ++j) s.r[j] = 0.0;
      }
    }
    from = to;
  }
}

void find_spikes(Search& s) {
  const std::vector<double> median = running_median(s.r);
  std::vector<double> d(s.r.size());
  for (std::size_t j = 0; j < d.size(); ++j) d[j] = s.r[j] - median[j];
  const double bound = kSpikeSigmas * std::max(s.sigma, mad_of(d));
  std::vector<std::size_t> out;
  for (std::size_t j = 0; j < d.size(); ++j)
    if (bound > 0.0 && std::abs(d[j]) > bound) out.push_back(j);
  for (std::size_t i = 0; i < out.size();) {
    std::size_t k = i + 1;
    while (k < out.size() && out[k] - out[k - 1] <= 3) ++k;
    if (out[k - 1] - out[i] + 1 <= kMaxSpikeSamples) {
      std::size_t top = out[i];
      double power = 0.0;
      for (std::size_t g = i; g < k; ++g) {
        power += d[out[g]] * d[out[g]];
        if (std::abs(d[out[g]]) > std::abs(d[top])) top = out[g];
        s.r[out[g]] = median[out[g]];
      }
      s.events.push_back({EventKind::kSpike, s.time[top], s.time[top], power / s.total, d[top]});
    }
    i = k;
  }
}

// Block mean squares of the cleaned residual (e) and of the prediction (q), what the record
// leaves without an event (x) and z = ln(e / x).
struct Blocks {
  std::size_t size = 0;  // samples a block
  std::vector<double> e, q, x, z;
};

// x_b (events.h): between a steady level and one in proportion to the motion, by the least
// median |ln(e / x)|.
std::vector<double> expected_energy(const Blocks& b, double floor) {
  const std::size_t count = b.e.size();
  double mean_q = 0.0;
  for (double q : b.q) mean_q += q / static_cast<double>(count);
  std::vector<double> best, shape(count), ratio(count), deviation(count);
  double best_spread = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i <= kExpectedGrid; ++i) {
    const double f = static_cast<double>(i) / static_cast<double>(kExpectedGrid);
    for (std::size_t k = 0; k < count; ++k) {
      shape[k] = (1.0 - f) + f * (mean_q > 0.0 ? b.q[k] / mean_q : 1.0);
      ratio[k] = b.e[k] / std::max(shape[k], 1e-300);
    }
    const double scale = median_of(ratio);
    std::vector<double> x(count);
    for (std::size_t k = 0; k < count; ++k) {
      x[k] = std::max(floor, scale * shape[k]);
      deviation[k] = std::abs(std::log(std::max(b.e[k], 1e-300) / x[k]));
    }
    if (const double spread = median_of(deviation); spread < best_spread) {
      best_spread = spread;
      best = std::move(x);
    }
  }
  return best;
}

Blocks blocks_of(const Search& s) {
  Blocks b;
  b.size = std::max<std::size_t>(4, static_cast<std::size_t>(std::lround(kBlockSeconds / s.dt)));
  const std::size_t count = s.r.size() / b.size;
  b.e.assign(count, 0.0);
  b.q.assign(count, 0.0);
  for (std::size_t k = 0; k < count * b.size; ++k) {
    b.e[k / b.size] += s.r[k] * s.r[k] / static_cast<double>(b.size);
    b.q[k / b.size] += s.prediction[k] * s.prediction[k] / static_cast<double>(b.size);
  }
  if (count == 0) return b;
  b.x = expected_energy(b, std::max(s.sigma * s.sigma, 1e-300));
  b.z.resize(count);
  for (std::size_t k = 0; k < count; ++k) b.z[k] = std::log(std::max(b.e[k], 1e-300) / b.x[k]);
  return b;
}

// Binary segmentation of z into the cuts it holds (block indices, sorted).
void segment(const std::vector<double>& z, std::size_t from, std::size_t to, double spread,
             std::vector<std::size_t>& cuts) {
  if (to - from < 4) return;
  double sum = 0.0;
  for (std::size_t k = from; k < to; ++k) sum += z[k];
  double left = 0.0, best = 0.0;
  std::size_t at = 0;
  for (std::size_t m = from + 1; m < to; ++m) {
    left += z[m - 1];
    const auto n1 = static_cast<double>(m - from), n2 = static_cast<double>(to - m);
    if (n1 < 2.0 || n2 < 2.0) continue;
    const double t = std::abs(left / n1 - (sum - left) / n2) * std::sqrt(n1 * n2 / (n1 + n2));
    if (t > best) best = t, at = m;
  }
  if (at == 0 || !(best > kChangeSigmas * spread)) return;
  cuts.push_back(at);
  segment(z, from, at, spread, cuts);
  segment(z, at, to, spread, cuts);
}

// The event of blocks [from, to) (events.h): a step change, a capacity drop, a burst, or none
// for a burst that ends with the record shorter than kMinStepSeconds (a correct model's edge).
std::optional<ResidualEvent> block_event(const Search& s, const Blocks& b, std::size_t from,
                                         std::size_t to) {
  const std::size_t first = from * b.size, last = to * b.size;
  double power = 0.0, sum = 0.0, before = 0.0, rp = 0.0, pp = 0.0;
  for (std::size_t j = first; j < last; ++j) {
    power += s.r[j] * s.r[j];
    sum += s.r[j];
    rp += s.r[j] * s.prediction[j];
    pp += s.prediction[j] * s.prediction[j];
  }
  for (std::size_t j = 0; j < first; ++j) before += s.r[j];
  const auto n = static_cast<double>(last - first);
  ResidualEvent e{EventKind::kBurst, s.time[first], s.time[last - 1], power / s.total,
                  std::sqrt(power / n)};
  const bool to_end = to == b.e.size();
  if (to_end && s.time[last - 1] - e.start < kMinStepSeconds) return std::nullopt;
  if (!to_end) return e;
  const double mean = sum / n;
  if (mean * mean >= 0.5 * power / n) {
    e.kind = EventKind::kStepChange;
    e.size = mean - (first > 0 ? before / static_cast<double>(first) : 0.0);
  } else if (pp > 0.0 && rp * rp >= kFollowsMotion * power * pp) {
    e.kind = rp < 0.0 ? EventKind::kCapacityDrop : EventKind::kStepChange;
    e.size = rp / pp;
    e.relative = true;
  }
  return e;
}

void find_changes(Search& s) {
  const Blocks b = blocks_of(s);
  if (b.z.size() < 8) return;
  std::vector<double> steps;
  for (std::size_t k = 1; k < b.z.size(); ++k) steps.push_back(b.z[k] - b.z[k - 1]);
  const double spread = std::max(mad_of(steps) / std::sqrt(2.0), 1e-6);
  std::vector<std::size_t> cuts{0, b.z.size()};
  segment(b.z, 0, b.z.size(), spread, cuts);
  std::sort(cuts.begin(), cuts.end());
  const double over = kEventFactor * kEventFactor;
  std::size_t open = b.z.size();  // the first block of the elevated run being gathered
  for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
    double e = 0.0, x = 0.0;
    for (std::size_t k = cuts[c]; k < cuts[c + 1]; ++k) e += b.e[k], x += b.x[k];
    const bool elevated = e >= over * x;
    if (elevated && open == b.z.size()) open = cuts[c];
    if (!elevated && open != b.z.size()) {
      if (const auto e = block_event(s, b, open, cuts[c])) s.events.push_back(*e);
      open = b.z.size();
    }
  }
  if (open != b.z.size())
    if (const auto e = block_event(s, b, open, b.z.size())) s.events.push_back(*e);
}

// At most kMaxEvents of each kind, the largest first.
void keep_largest(std::vector<ResidualEvent>& events) {
  std::stable_sort(
      events.begin(), events.end(),
      [](const ResidualEvent& a, const ResidualEvent& b) { return a.share > b.share; });
  std::vector<ResidualEvent> kept;
  for (const auto& e : events) {
    const auto same = std::count_if(kept.begin(), kept.end(),
                                    [&](const ResidualEvent& k) { return k.kind == e.kind; });
    if (static_cast<std::size_t>(same) < kMaxEvents) kept.push_back(e);
  }
  events = std::move(kept);
}

}  // namespace

std::vector<ResidualEvent> find_events(std::span<const double> time,
                                       std::span<const double> reading,
                                       std::span<const double> prediction, double dt,
                                       double sigma) {
  if (time.size() != reading.size() || prediction.size() != reading.size() || !(dt > 0.0) ||
      !(sigma >= 0.0))
    throw std::invalid_argument(
        "find_events: time, reading and prediction of one size, dt > 0 and sigma >= 0");
  Search s{time, reading, prediction, {}, 0.0, sigma, dt, {}};
  s.r.resize(reading.size());
  for (std::size_t j = 0; j < s.r.size(); ++j) {
    s.r[j] = reading[j] - prediction[j];
    s.total += s.r[j] * s.r[j];
  }
  if (!(s.total > 0.0) || s.r.size() < 2 * kMedianSpan) return {};
  find_held(s);
  find_spikes(s);
  find_changes(s);
  keep_largest(s.events);
  return s.events;
}

std::string event_name(EventKind kind) {
  switch (kind) {
    case EventKind::kHeldSample: return "held_sample";
    case EventKind::kSpike: return "spike";
    case EventKind::kStepChange: return "step_change";
    case EventKind::kCapacityDrop: return "capacity_drop";
    case EventKind::kBurst: break;
  }
  return "burst";
}

}  // namespace rths::identify
