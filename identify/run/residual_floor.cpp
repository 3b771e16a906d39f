#include "identify/run/residual_floor.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "identify/model/model.h"
#include "identify/residual/locate.h"
#include "identify/run/run_residual.h"
#include "identify/run/sensors.h"

namespace rths::identify {
namespace {

// The samples a channel is judged on (residual_floor.h): the signals, the reported model's
// prediction p and the residual r = y - p, less kEdgeSeconds at either end; all of them when
// too few would be left.
struct Judged {
  std::vector<double> time, input, velocity, prediction, reading, residual;
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
  Judged out{cut(s.time), cut(s.input), cut(s.velocity), cut(p), cut(s.target), cut(s.target)};
  for (std::size_t j = 0; j < out.residual.size(); ++j) out.residual[j] -= out.prediction[j];
  return out;
}

// The samples of `j` where `inside` holds (all of them where it is empty).
Judged subset(const Judged& j, const std::vector<bool>& inside) {
  if (inside.empty()) return j;
  Judged out;
  for (std::size_t k = 0; k < j.residual.size(); ++k) {
    if (!inside[k]) continue;
    for (auto [from, to] : {std::pair{&j.time, &out.time},
                            {&j.input, &out.input},
                            {&j.velocity, &out.velocity},
                            {&j.prediction, &out.prediction},
                            {&j.reading, &out.reading},
                            {&j.residual, &out.residual}})
      if (k < from->size()) to->push_back((*from)[k]);
  }
  return out;
}

// Whether one value holds more than a bin's share (1 / kRelationBins) of x: equal-count bins of x
// would then split that value's samples by their order in time, not by x (a held reading, a
// signal at rest), and any residual that moves in time would seem a function of x.
bool mostly_one_value(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  std::size_t longest = 0;
  for (std::size_t a = 0, b = 0; a < x.size(); a = b) {
    while (b < x.size() && x[b] == x[a]) ++b;
    longest = std::max(longest, b - a);
  }
  return longest * kRelationBins > x.size();
}

struct Relation {
  std::string signal;      // empty: none at kMinRelation
  double explained = 0.0;  // of r's variance
  std::string as;          // the line through r against the signal, in words; empty: no line
};

// r's least-squares line on x (about their means): (slope, share of r's variance it explains).
std::pair<double, double> line_of(const std::vector<double>& x, const std::vector<double>& r) {
  double mx = 0.0, mr = 0.0;
  for (std::size_t k = 0; k < r.size(); ++k) {
    mx += x[k] / static_cast<double>(r.size());
    mr += r[k] / static_cast<double>(r.size());
  }
  double xx = 0.0, xr = 0.0, rr = 0.0;
  for (std::size_t k = 0; k < r.size(); ++k) {
    xx += (x[k] - mx) * (x[k] - mx);
    xr += (x[k] - mx) * (r[k] - mr);
    rr += (r[k] - mr) * (r[k] - mr);
  }
  return xx > 0.0 && rr > 0.0 ? std::pair{xr / xx, xr * xr / (xx * rr)} : std::pair{0.0, 0.0};
}

// "+35 %": a signed share.
std::string signed_percent(double ratio) {
  std::string out = number_text(100.0 * ratio) + " %";
  if (ratio >= 0.0) out.insert(out.begin(), '+');
  return out;
}

// The line of r on candidate `which` (0 the input, 1 its rate, 2 the model's output) in the
// words a lab reads it by: a gain, a stiffness, a lead, a damping, measured / model.
std::string line_words(Channel channel, int which, double slope) {
  const bool force = channel == Channel::kForce;
  if (which == 2) return "as measured / model " + signed_percent(slope);
  if (which == 0)
    return force ? "as a stiffness of " + number_text(slope) + " N/m"
                 : "as a gain of " + signed_percent(slope) + " on the command";
  if (force) return "as a damping of " + number_text(slope) + " N s/m";
  std::string lead = number_text(1e3 * slope) + " ms";
  if (slope >= 0.0) lead.insert(lead.begin(), '+');
  return "as the reading ahead of the model by " + lead;
}

// The signal r depends on most over the samples where `inside` holds (the channel's input, its
// rate, the model's output), named when a function of it explains at least kMinRelation of r's
// variance there.
Relation relation(const Judged& all, Channel channel, const std::vector<bool>& inside) {
  const Judged j = subset(all, inside);
  const std::string input = channel == Channel::kMeasured ? "the command" : "the displacement read";
  const std::vector<std::pair<std::string, const std::vector<double>*>> candidates{
      {input, &j.input},
      {"the rate of " + input, &j.velocity},
      {"the model's output", &j.prediction}};
  Relation out;
  for (int which = 0; which < 3; ++which) {
    const auto& [name, x] = candidates[static_cast<std::size_t>(which)];
    if (mostly_one_value(*x)) continue;
    const double e = correlation_ratio(*x, j.residual);
    if (!(e >= kMinRelation && e > out.explained)) continue;
    // The line is said where it holds half of what the map holds: else r depends on the signal's
    // sign or size, not in proportion to it.
    const auto [slope, line] = line_of(*x, j.residual);
    out = {name, e, line >= 0.5 * e ? line_words(channel, which, slope) : ""};
  }
  return out;
}

// Whether each judged sample lies inside one of `windows` (s).
template <class Window>
std::vector<bool> inside_windows(const Judged& j, const std::vector<Window>& windows, double dt) {
  std::vector<bool> out(j.time.size(), false);
  for (const auto& w : windows)
    for (std::size_t k = 0; k < j.time.size(); ++k)
      if (j.time[k] >= w.start - 0.5 * dt && j.time[k] <= w.end + 0.5 * dt) out[k] = true;
  return out;
}

// The relation over the record, or over the windows that hold the residual where it is stronger
// there (a residual of a few seconds relates to the signals inside them, not outside).
void set_relation(const Judged& j, double dt, ChannelFloor& out) {
  const Relation whole = relation(j, out.channel, {});
  const Relation windowed = out.windows.empty()
                                ? Relation{}
                                : relation(j, out.channel, inside_windows(j, out.windows, dt));
  const bool in_windows = windowed.explained > whole.explained;
  out.relation = in_windows ? windowed.signal : whole.signal;
  out.explained = in_windows ? windowed.explained : whole.explained;
  out.relation_in_windows = in_windows && !windowed.signal.empty();
  out.relation_as = in_windows ? windowed.as : whole.as;
}

// The events on the judged samples (events.h) and the part they are on (residual_floor.h).
void set_events(const Judged& j, double dt, double sigma, ChannelFloor& out) {
  if (j.reading.size() != j.prediction.size()) return;
  out.events = find_events(j.time, j.reading, j.prediction, dt, sigma);
  out.time = j.time;
  out.inside_events.assign(j.time.size(), 0.0);
  const std::vector<bool> inside = inside_windows(j, out.events, dt);
  for (std::size_t k = 0; k < j.time.size(); ++k)
    if (inside[k]) out.inside_events[k] = j.residual[k];
  const std::string n = std::to_string(out.actuator);
  const bool moved_only = std::all_of(out.events.begin(), out.events.end(), [](const auto& e) {
    return e.kind == EventKind::kCapacityDrop;
  });
  // The reading's where held readings, spikes and step changes hold more of the residual's power
  // than the motion's events (bursts, capacity drops).
  double read_share = 0.0, moved_share = 0.0;
  for (const auto& e : out.events)
    (e.kind != EventKind::kBurst && e.kind != EventKind::kCapacityDrop ? read_share
                                                                       : moved_share) += e.share;
  const bool read = read_share > moved_share;
  if (out.channel == Channel::kMeasured) {
    out.events_part = (read ? "displacement sensor " : "actuator ") + n;
    return;
  }
  // A reading that stood still or jumped follows the motion only by not moving with it: its
  // residual is the model's output less a constant. Else, inside the events, a force that follows
  // the motion is the specimen's (as above the floor).
  if (read) {
    out.events_part = "load cell " + n;
    if (out.above) out.part = out.events_part;
    return;
  }
  const bool follows = !out.events.empty() && !relation(j, out.channel, inside).signal.empty();
  out.events_part = moved_only || follows ? "specimen " + n
                    : out.above           ? out.part
                                          : "load cell " + n;
}

void set_above(const Judged& j, double dt, ChannelFloor& out);

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
  const Judged j = judged(s, prediction_without(path, channel, not_named_on(path, channel)));
  double power = 0.0;
  for (double x : j.residual) power += x * x;
  out.level =
      spread > 0.0 ? std::sqrt(power / static_cast<double>(j.residual.size())) / spread : 0.0;
  out.band_noise = spread > 0.0 ? rms_above(j.residual, s.dt, s.input_cutoff) / spread : 0.0;
  out.band_hz = s.input_cutoff;
  out.floor = std::max({out.noise, out.band_noise, kModelFloor});
  out.above = out.level > kFloorFactor * out.floor;
  if (out.above) set_above(j, s.dt, out);
  set_events(j, s.dt, out.floor * spread, out);
  return out;
}

// Where, when and at what frequencies a channel above its floor lies, and its part.
void set_above(const Judged& j, double dt, ChannelFloor& out) {
  out.windows = residual_windows(j.time, j.residual);
  const ResidualBand band = residual_band(j.residual, dt);
  out.peak_hz = band.peak_hz;
  out.band_low_hz = band.low_hz;
  out.band_high_hz = band.high_hz;
  set_relation(j, dt, out);
  // A force that follows no motion is read, not done: the load cell's (residual_floor.h).
  if (out.channel == Channel::kForce && out.relation.empty())
    out.part = "load cell " + std::to_string(out.actuator);
  out.excess = 1.0 - (out.floor / out.level) * (out.floor / out.level);
}

// Whether the largest of `events` (by share) lies within a held reading of `displacement`.
bool overlaps_held_reading(const std::vector<ResidualEvent>& events,
                           const std::vector<ResidualEvent>& displacement) {
  const auto largest = std::max_element(
      events.begin(), events.end(), [](const auto& a, const auto& b) { return a.share < b.share; });
  return largest != events.end() &&
         std::any_of(displacement.begin(), displacement.end(), [&](const ResidualEvent& held) {
           return held.kind == EventKind::kHeldSample && largest->start <= held.end &&
                  largest->end >= held.start;
         });
}

// "401 N", "12 N RMS", "25 N change", "measured / model -30 % from then on".
std::string event_size(const ResidualEvent& e, const std::string& unit) {
  if (e.relative) return "measured / model " + number_text(100.0 * e.size) + " % from then on";
  const std::string value = number_text(e.size) + " " + unit;
  if (e.kind == EventKind::kSpike) return value;
  return value + (e.kind == EventKind::kStepChange ? " change" : " RMS");
}

// [{kind, start_s, end_s, share, size, unit}] of the channel's events.
nlohmann::json events_json(const ChannelFloor& f) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& e : f.events)
    out.push_back({{"kind", event_name(e.kind)},
                   {"start_s", e.start},
                   {"end_s", e.end},
                   {"share", e.share},
                   {"size", e.size},
                   {"unit", e.relative                     ? "measured / model - 1"
                            : f.channel == Channel::kForce ? "N"
                                                           : "m"}});
  return out;
}

}  // namespace

std::vector<ChannelFloor> channel_floors(const ActuatorPath& path) {
  std::vector<ChannelFloor> out;
  for (Channel channel : {Channel::kMeasured, Channel::kForce})
    if (path.id.find(channel)) out.push_back(channel_floor(path, channel));
  // The force model runs on the displacement read: where that reading held, the force's events
  // over the same time are the displacement sensor's.
  if (out.size() == 2 && overlaps_held_reading(out[1].events, out[0].events))
    out[1].events_part = "displacement sensor " + std::to_string(path.actuator);
  return out;
}

std::string ChannelFloor::floor_source() const {
  std::string out = "the sensor's noise " + percent_text(noise);
  if (band_hz > 0.0)
    out += ", the residual above the model's " + fixed_text(band_hz, 1) + " Hz input band " +
           percent_text(band_noise);
  return out;
}

std::string ChannelFloor::text() const {
  std::string out = "above the floor on " + part + " (" + channel_word + "): residual " +
                    percent_text(level) + " of the signal's std, " + fixed_text(level / floor, 1) +
                    " x its floor " + percent_text(floor) + " (" + floor_source() + "); " +
                    fixed_text(100.0 * excess, 0) + " % of the residual's power above the floor; ";
  if (windows.empty()) out += "spread over the record";
  for (std::size_t i = 0; i < windows.size(); ++i)
    out += (i ? ", " : "in ") + fixed_text(windows[i].start, 2) + "-" +
           fixed_text(windows[i].end, 2) + " s (" + fixed_text(100.0 * windows[i].share, 0) + " %)";
  out += "; at " + fixed_text(peak_hz, 2) + " Hz (80 % of its power within " +
         fixed_text(band_low_hz, 2) + "-" + fixed_text(band_high_hz, 2) + " Hz); ";
  return out +
         (relation.empty()
              ? "no function of the input, its rate or the model's output explains " +
                    fixed_text(100.0 * kMinRelation, 0) + " % of it"
              : "a function of " + relation + " explains " + fixed_text(100.0 * explained, 0) +
                    " % of it" + (relation_in_windows ? " inside those windows" : "") +
                    (relation_as.empty() ? ", not in proportion (its sign or its size matter)"
                                         : ", " + relation_as));
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
      {"relation_in_windows", relation_in_windows},
      {"relation_as", relation_as},
      {"excess", excess},
      {"events", events_json(*this)},
      {"text", above ? text() : std::string()}};
}

std::string ChannelFloor::events_text() const {
  std::string out = "located in time on " + events_part + " (" + channel_word + "):";
  for (std::size_t i = 0; i < events.size(); ++i) {
    const ResidualEvent& e = events[i];
    out += (i ? "; " : " ") + event_name(e.kind) + " at " + fixed_text(e.start, 3);
    if (e.end > e.start) out += "-" + fixed_text(e.end, 3);
    out += " s, " + event_size(e, channel == Channel::kForce ? "N" : "m") + " (" +
           fixed_text(100.0 * e.share, 1) + " % of the residual's power)";
  }
  return out + (events_share ? "; the re-run with them put back: share " +
                                   fixed_text(100.0 * *events_share, 0) + " %"
                             : "; not re-run, no share");
}

std::string unexplained_section(const std::vector<Unexplained>& unexplained,
                                const std::vector<ChannelFloor>& floors) {
  std::string out = "unexplained, every part and channel:";
  const bool reported =
      std::any_of(floors.begin(), floors.end(), [](const ChannelFloor& f) { return f.reported(); });
  if (unexplained.empty() && !reported) {
    out += " none (every channel at its floor, residual against floor, of the signal's std:";
    for (std::size_t i = 0; i < floors.size(); ++i)
      out += (i ? "; " : " ") + floors[i].part + " (" + floors[i].channel_word + ") " +
             percent_text(floors[i].level) + " against " + percent_text(floors[i].floor) + " (" +
             floors[i].floor_source() + ")";
    return out + "; above is over " + fixed_text(kFloorFactor, 0) + " x the floor)\n";
  }
  out += "\n";
  for (const auto& u : unexplained) out += "  " + u.text() + "\n";
  for (const auto& f : floors) {
    if (f.above) out += "  " + f.text() + "\n";
    if (!f.events.empty()) out += "  " + f.events_text() + "\n";
  }
  return out;
}

nlohmann::json unexplained_json(const std::vector<Unexplained>& unexplained,
                                const std::vector<ChannelFloor>& floors) {
  nlohmann::json out = json_array(unexplained);
  for (const auto& f : floors) {
    if (f.events.empty()) continue;
    std::vector<std::string> kinds{"time_varying"};
    for (const auto& e : f.events)
      if (std::find(kinds.begin(), kinds.end(), event_name(e.kind)) == kinds.end())
        kinds.push_back(event_name(e.kind));
    out.push_back(
        {{"part", f.events_part},
         {"channel", f.channel_word},
         {"share_pct", f.events_share ? nlohmann::json(100.0 * *f.events_share) : nlohmann::json()},
         {"kinds", kinds},
         {"when", events_json(f)},
         {"text", f.events_text()}});
  }
  return out;
}

std::vector<Unexplained> event_residuals(const std::vector<ChannelFloor>& floors) {
  std::vector<Unexplained> out;
  for (const auto& f : floors) {
    if (f.events.empty()) continue;
    Unexplained u;
    u.actuator = f.actuator;
    u.channel = f.channel;
    u.part = f.events_part;
    u.channel_word = f.channel_word + " events";
    u.time = f.time;
    u.description.described = f.inside_events;
    out.push_back(std::move(u));
  }
  return out;
}

void set_event_shares(const std::vector<ResidualShare>& described,
                      std::vector<ChannelFloor>& floors) {
  for (auto& f : floors)
    for (const auto& s : described)
      if (!f.events.empty() && s.link == f.events_part && s.effect == f.channel_word + " events")
        f.events_share = s.share;
}

}  // namespace rths::identify
