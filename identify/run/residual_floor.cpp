#include "identify/run/residual_floor.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "identify/model/model.h"
#include "identify/model/spectra.h"
#include "identify/run/run_residual.h"
#include "identify/run/sensors.h"

namespace rths::identify {
namespace {

// The prediction of the model the report stands by, at every sample: `channel`'s final model
// without the effects the description beat (ActuatorPath::not_named: named nowhere), as
// unexplained.h describes its residual.
std::vector<double> reported_prediction(const ActuatorPath& path, Channel channel) {
  const ChannelIdentification* c = path.id.find(channel);
  const ChannelSignals& s = identified_signals(path.id, channel);
  const SignalScales scales = signal_scales(s);
  ChannelModel model = c->final_fit.model;
  bool reduced = false;
  for (const auto& n : path.not_named)
    if (n.channel == channel) {
      model = without_named(model, path, n.effect, scales);
      reduced = true;
    }
  if (!reduced && c->final_fit.prediction.size() == s.size()) return c->final_fit.prediction;
  return predict(model, s);
}

// The peak of r's power spectrum and the band of the middle 80 % of its power (Hz, DC left out).
void set_band(const std::vector<double>& r, double dt, ChannelFloor& out) {
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
  if (!(total > 0.0)) return;
  double cumulative = 0.0;
  bool low = false;
  for (std::size_t k = 1; k < s.amplitude.size(); ++k) {
    cumulative += s.amplitude[k] * s.amplitude[k];
    if (!low && cumulative >= 0.1 * total) {
      out.band_low_hz = s.frequency[k];
      low = true;
    }
    if (cumulative >= 0.9 * total) {
      out.band_high_hz = s.frequency[k];
      return;
    }
  }
}

// RMS of r above `cutoff` (Hz) from its spectrum's power share there; 0 without a cutoff.
double rms_above(const std::vector<double>& r, double dt, double cutoff) {
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

// The samples a channel is judged on (residual_floor.h): the signals, the reported model's
// prediction p and the residual r = y - p, less kEdgeSeconds at either end; all of them when
// too few would be left.
struct Judged {
  std::vector<double> time, input, velocity, prediction, residual;
};

Judged judged(const ChannelSignals& s, const std::vector<double>& p) {
  std::size_t first = 0, last = p.size();
  while (first < last && s.time[first] < s.time.front() + kEdgeSeconds) ++first;
  while (last > first && s.time[last - 1] > s.time.back() - kEdgeSeconds) --last;
  if (last - first < 4 * kFloorWindows) first = 0, last = p.size();
  const auto cut = [&](const std::vector<double>& x) {
    return x.size() == p.size()
               ? std::vector<double>(x.begin() + static_cast<std::ptrdiff_t>(first),
                                     x.begin() + static_cast<std::ptrdiff_t>(last))
               : std::vector<double>{};
  };
  Judged out{cut(s.time), cut(s.input), cut(s.velocity), cut(p), cut(s.target)};
  for (std::size_t j = 0; j < out.residual.size(); ++j) out.residual[j] -= out.prediction[j];
  return out;
}

// The share of r's variance a function of x explains, with no form presumed: r's mean in
// kRelationBins bins of equal count over x (the correlation ratio). A least-squares fit leaves r
// uncorrelated with whatever its model holds linearly (a gain on the command), so a straight
// correlation misses a dependence a map finds (the cubic part of a stroke).
double explained_by(const std::vector<double>& x, const std::vector<double>& r) {
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

// The signal r depends on most (the channel's input, its rate, the model's output), named when a
// function of it explains at least kMinRelation of r's variance.
void set_relation(const Judged& j, ChannelFloor& out) {
  const std::string input =
      out.channel == Channel::kMeasured ? "the command" : "the displacement read";
  const std::vector<std::pair<std::string, const std::vector<double>*>> candidates{
      {input, &j.input},
      {"the rate of " + input, &j.velocity},
      {"the model's output", &j.prediction}};
  for (const auto& [name, x] : candidates) {
    const double e = explained_by(*x, j.residual);
    if (e >= kMinRelation && e > out.explained) {
      out.relation = name;
      out.explained = e;
    }
  }
}

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << value;
  return out.str();
}

ChannelFloor channel_floor(const ActuatorPath& path, Channel channel) {
  const ChannelSignals& s = identified_signals(path.id, channel);
  const bool force = channel == Channel::kForce;
  ChannelFloor out;
  out.actuator = path.actuator;
  out.channel = channel;
  out.part = (force ? "specimen " : "actuator ") + std::to_string(path.actuator);
  out.channel_word = force ? "force" : "displacement";
  const double spread = noise_spread(path.id, channel);
  const double noise =
      std::max(force ? path.force_noise : path.displacement_noise,
               force ? path.declared_force_noise : path.declared_displacement_noise);
  out.noise = spread > 0.0 ? noise / spread : 0.0;
  const Judged j = judged(s, reported_prediction(path, channel));
  double power = 0.0;
  for (double x : j.residual) power += x * x;
  out.level =
      spread > 0.0 ? std::sqrt(power / static_cast<double>(j.residual.size())) / spread : 0.0;
  out.band_noise = spread > 0.0 ? rms_above(j.residual, s.dt, s.input_cutoff) / spread : 0.0;
  out.band_hz = s.input_cutoff;
  out.floor = std::max({out.noise, out.band_noise, kModelFloor});
  out.above = out.level > kFloorFactor * out.floor;
  if (!out.above) return out;
  out.windows = residual_windows(j.time, j.residual);
  set_band(j.residual, s.dt, out);
  set_relation(j, out);
  // A force that follows no motion is read, not done: the load cell's (residual_floor.h).
  if (force && out.relation.empty()) out.part = "load cell " + std::to_string(path.actuator);
  out.excess = 1.0 - (out.floor / out.level) * (out.floor / out.level);
  return out;
}

}  // namespace

std::vector<ResidualWindow> residual_windows(const std::vector<double>& time,
                                             const std::vector<double>& residual) {
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

std::vector<ChannelFloor> channel_floors(const ActuatorPath& path) {
  std::vector<ChannelFloor> out;
  for (Channel channel : {Channel::kMeasured, Channel::kForce})
    if (path.id.find(channel)) out.push_back(channel_floor(path, channel));
  return out;
}

std::string ChannelFloor::floor_source() const {
  std::string out = "the sensor's noise " + percent_text(noise);
  if (band_hz > 0.0)
    out += ", the residual above the model's " + fixed(band_hz, 1) + " Hz input band " +
           percent_text(band_noise);
  return out;
}

std::string ChannelFloor::text() const {
  std::string out = "above the floor on " + part + " (" + channel_word + "): residual " +
                    percent_text(level) + " of the signal's std, " + fixed(level / floor, 1) +
                    " x its floor " + percent_text(floor) + " (" + floor_source() + "); " +
                    fixed(100.0 * excess, 0) + " % of the residual's power above the floor; ";
  if (windows.empty()) out += "spread over the record";
  for (std::size_t i = 0; i < windows.size(); ++i)
    out += (i ? ", " : "in ") + fixed(windows[i].start, 2) + "-" + fixed(windows[i].end, 2) +
           " s (" + fixed(100.0 * windows[i].share, 0) + " %)";
  out += "; at " + fixed(peak_hz, 2) + " Hz (80 % of its power within " + fixed(band_low_hz, 2) +
         "-" + fixed(band_high_hz, 2) + " Hz); ";
  return out + (relation.empty()
                    ? "no function of the input, its rate or the model's output explains " +
                          fixed(100.0 * kMinRelation, 0) + " % of it"
                    : "a function of " + relation + " explains " + fixed(100.0 * explained, 0) +
                          " % of it");
}

nlohmann::json ChannelFloor::json() const {
  nlohmann::json w = nlohmann::json::array();
  for (const auto& x : windows)
    w.push_back({{"start_s", x.start}, {"end_s", x.end}, {"share", x.share}});
  return {
      {"part", part},
      {"channel", channel_word},
      {"residual", level},
      {"floor", floor},
      {"noise", noise},
      {"band_noise", band_noise},
      {"band_hz", band_hz},
      {"factor", kFloorFactor},
      {"above", above},
      {"windows", w},
      {"peak_hz", above ? nlohmann::json(peak_hz) : nlohmann::json()},
      {"residual_band_hz", above ? nlohmann::json{band_low_hz, band_high_hz} : nlohmann::json()},
      {"relation", relation},
      {"relation_explained", explained},
      {"excess", excess},
      {"text", above ? text() : std::string()}};
}

std::string unexplained_section(const std::vector<Unexplained>& unexplained,
                                const std::vector<ChannelFloor>& floors) {
  std::string out = "unexplained, every part and channel:";
  const bool above =
      std::any_of(floors.begin(), floors.end(), [](const ChannelFloor& f) { return f.above; });
  if (unexplained.empty() && !above) {
    out += " none (every channel at its floor, residual against floor, of the signal's std:";
    for (std::size_t i = 0; i < floors.size(); ++i)
      out += (i ? "; " : " ") + floors[i].part + " (" + floors[i].channel_word + ") " +
             percent_text(floors[i].level) + " against " + percent_text(floors[i].floor) + " (" +
             floors[i].floor_source() + ")";
    return out + "; above is over " + fixed(kFloorFactor, 0) + " x the floor)\n";
  }
  out += "\n";
  for (const auto& u : unexplained) out += "  " + u.text() + "\n";
  for (const auto& f : floors)
    if (f.above) out += "  " + f.text() + "\n";
  return out;
}

nlohmann::json floors_json(const std::vector<ChannelFloor>& floors) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& f : floors) out.push_back(f.json());
  return out;
}

}  // namespace rths::identify
