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

// The final model's residual r = y - p of `channel`, at every sample of its signals.
std::vector<double> final_residual(const ActuatorPath& path, Channel channel) {
  const ChannelIdentification* c = path.id.find(channel);
  if (!c) return {};
  const ChannelSignals& s = identified_signals(path.id, channel);
  std::vector<double> p = c->final_fit.prediction;
  if (p.size() != s.size()) p = predict(c->final_fit.model, s);
  std::vector<double> r(s.size());
  for (std::size_t j = 0; j < r.size(); ++j) r[j] = s.target[j] - p[j];
  return r;
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

std::vector<double> signs(const std::vector<double>& x) {
  std::vector<double> out(x.size());
  for (std::size_t j = 0; j < x.size(); ++j) out[j] = x[j] > 0.0 ? 1.0 : (x[j] < 0.0 ? -1.0 : 0.0);
  return out;
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

// The signal r correlates with most (input, its rate, their signs), named when |corr| reaches
// kMinCorrelation.
void set_relation(const std::vector<double>& r, const ChannelSignals& s, ChannelFloor& out) {
  const std::string input =
      s.channel == Channel::kMeasured ? "the command" : "the displacement read";
  const std::vector<std::pair<std::string, std::vector<double>>> candidates{
      {input, s.input},
      {"the rate of " + input, s.velocity},
      {"the sign of " + input, signs(s.input)},
      {"the sign of the rate of " + input, signs(s.velocity)}};
  for (const auto& [name, x] : candidates) {
    if (x.size() != r.size()) continue;
    const double c = correlation(x, r);
    if (std::abs(c) >= kMinCorrelation && std::abs(c) > std::abs(out.correlation)) {
      out.relation = name;
      out.correlation = c;
    }
  }
}

// The samples a channel is judged on (residual_floor.h): its residual and signals less
// kEdgeSeconds at either end; all of them when too few would be left.
struct Judged {
  ChannelSignals signals;  // channel, dt, time, input and velocity only
  std::vector<double> residual;
};

Judged judged(const ChannelSignals& s, const std::vector<double>& r) {
  std::size_t first = 0, last = r.size();
  while (first < last && s.time[first] < s.time.front() + kEdgeSeconds) ++first;
  while (last > first && s.time[last - 1] > s.time.back() - kEdgeSeconds) --last;
  if (last - first < 4 * kFloorWindows) first = 0, last = r.size();
  const auto cut = [&](const std::vector<double>& x) {
    return x.size() == r.size()
               ? std::vector<double>(x.begin() + static_cast<std::ptrdiff_t>(first),
                                     x.begin() + static_cast<std::ptrdiff_t>(last))
               : std::vector<double>{};
  };
  Judged out;
  out.signals.channel = s.channel;
  out.signals.dt = s.dt;
  out.signals.time = cut(s.time);
  out.signals.input = cut(s.input);
  out.signals.velocity = cut(s.velocity);
  out.residual = cut(r);
  return out;
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
  const Judged j = judged(s, final_residual(path, channel));
  double power = 0.0;
  for (double x : j.residual) power += x * x;
  out.level =
      spread > 0.0 ? std::sqrt(power / static_cast<double>(j.residual.size())) / spread : 0.0;
  out.band_noise = spread > 0.0 ? rms_above(j.residual, s.dt, s.input_cutoff) / spread : 0.0;
  out.band_hz = s.input_cutoff;
  out.floor = std::max({out.noise, out.band_noise, kModelFloor});
  out.above = out.level > kFloorFactor * out.floor;
  if (!out.above) return out;
  out.windows = residual_windows(j.signals.time, j.residual);
  set_band(j.residual, s.dt, out);
  set_relation(j.residual, j.signals, out);
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
                    ? "follows neither the input, its rate nor their signs (|corr| < " +
                          fixed(kMinCorrelation, 1) + ")"
                    : "follows " + relation + " (corr " + fixed(correlation, 2) + ")");
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
      {"correlation", correlation},
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
