#include "identify/run/response_floor.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "identify/fit/effect_parameters.h"
#include "identify/run/residual_floor.h"
#include "identify/run/unexplained.h"

namespace rths::identify {
namespace {

// r's least-squares line over t: its values at every sample and the share of r's variance it
// explains.
std::pair<std::vector<double>, double> line_over_time(const std::vector<double>& t,
                                                      const std::vector<double>& r) {
  const auto n = static_cast<double>(r.size());
  double mt = 0.0, mr = 0.0;
  for (std::size_t j = 0; j < r.size(); ++j) {
    mt += t[j] / n;
    mr += r[j] / n;
  }
  double tt = 0.0, tr = 0.0, rr = 0.0;
  for (std::size_t j = 0; j < r.size(); ++j) {
    tt += (t[j] - mt) * (t[j] - mt);
    tr += (t[j] - mt) * (r[j] - mr);
    rr += (r[j] - mr) * (r[j] - mr);
  }
  const double slope = tt > 0.0 ? tr / tt : 0.0;
  std::vector<double> line(r.size());
  for (std::size_t j = 0; j < r.size(); ++j) line[j] = mr + slope * (t[j] - mt);
  return {line, tt > 0.0 && rr > 0.0 ? tr * tr / (tt * rr) : 0.0};
}

// `x` (at `from`, s, increasing) at the times `to` (s), the nearest earlier sample; 0 outside it.
std::vector<double> at_times(const std::vector<double>& from, const std::vector<double>& x,
                             const std::vector<double>& to) {
  std::vector<double> out(to.size(), 0.0);
  for (std::size_t j = 0; j < to.size(); ++j) {
    const auto i = std::upper_bound(from.begin(), from.end(), to[j]) - from.begin();
    if (i > 0) out[j] = x[static_cast<std::size_t>(i - 1)];
  }
  return out;
}

// The force channel's slow part on `path` (response_floor.h force), against e at `time`.
std::optional<ForceTrend> force_trend(const ActuatorPath& path, const std::vector<double>& time,
                                      const std::vector<double>& e) {
  if (!path.id.find(Channel::kForce)) return std::nullopt;
  const ChannelSignals& s = identified_signals(path.id, Channel::kForce);
  std::vector<std::string> without = not_named_on(path, Channel::kForce);
  if (path.id.find(Channel::kForce)->final_fit.model.has(Effect::kOffsetDrift) &&
      std::find(without.begin(), without.end(), "offset_drift") == without.end())
    without.push_back("offset_drift");
  const std::vector<double> r = minus(s.target, prediction_without(path, Channel::kForce, without));
  const auto [line, explained] = line_over_time(s.time, r);
  if (explained < kMinRelation) return std::nullopt;
  ForceTrend out;
  out.actuator = path.actuator;
  out.change = line.back() - line.front();
  out.explained = explained;
  if (path.fitted_stiffness > 0.0) out.as_travel = out.change / path.fitted_stiffness;
  out.of_response = correlation_ratio(at_times(s.time, line, time), e);
  return out;
}

// The RMS of x over [from, to) of its samples.
double rms_over(const std::vector<double>& x, std::size_t from, std::size_t to) {
  double sum = 0.0;
  for (std::size_t j = from; j < to; ++j) sum += x[j] * x[j];
  return to > from ? std::sqrt(sum / static_cast<double>(to - from)) : 0.0;
}

bool silent(const RunIdentification& run) {
  return run.unexplained.empty() &&
         std::none_of(run.floors.begin(), run.floors.end(),
                      [](const ChannelFloor& f) { return f.reported(); });
}

// Where, when and at what frequencies the re-run's error lies (response_floor.h), at column i.
void locate(const RunIdentification& run, Eigen::Index i, ResponseFloor& out) {
  const RunResidual& r = *run.residual;
  const auto n = static_cast<std::size_t>(r.recorded_response.rows());
  std::vector<double> e(n), u(n);
  for (std::size_t j = 0; j < n; ++j) {
    const auto k = static_cast<Eigen::Index>(j);
    u[j] = r.recorded_response(k, i);
    e[j] = r.identified_response(k, i) - u[j];
  }
  if (n < 2 * kRelationBins || n < kFloorWindows || r.time.size() < n) return;
  const std::vector<double> time(r.time.begin(), r.time.begin() + static_cast<std::ptrdiff_t>(n));
  out.windows = residual_windows(time, e);
  out.band = residual_band(e, time[1] - time[0]);
  const double first = rms_over(e, 0, n / 4);
  out.growth = first > 0.0 ? rms_over(e, n - n / 4, n) / first : 0.0;
  out.of_time = correlation_ratio(time, e);
  out.of_displacement = correlation_ratio(u, e);
  for (const ActuatorPath& path : run.actuators)
    if (auto t = force_trend(path, time, e)) out.force.push_back(*t);
}

}  // namespace

std::optional<ResponseFloor> response_floor(const RunIdentification& run) {
  if (!run.residual || run.residual->floors.empty()) return std::nullopt;
  const RunResidual& r = *run.residual;
  ResponseFloor out;
  out.error = r.identified;
  out.noise_floor = r.noise_floor;
  out.floor = std::max(r.noise_floor, kMinResponseFloor);
  out.above = out.error > kResponseFloorFactor * out.floor;
  std::size_t worst = 0;
  for (std::size_t i = 0; i < r.floors.size(); ++i)
    if (r.floors[i].identified > r.floors[worst].identified) worst = i;
  out.dof = r.floors[worst].dof;
  if (!out.above) return out;
  out.silent = silent(run);
  if (r.identified_response.cols() > static_cast<Eigen::Index>(worst))
    locate(run, static_cast<Eigen::Index>(worst), out);
  return out;
}

namespace {

// "actuator 1's force channel, against its model without an offset drift, drifts -666 N ...".
std::string force_text(const ForceTrend& f) {
  std::string out = "actuator " + std::to_string(f.actuator) +
                    "'s force channel, against its model without an offset drift, moves " +
                    number_text(f.change) + " N over the record in a line (explaining " +
                    fixed_text(100.0 * f.explained, 0) + " % of that residual)";
  if (f.as_travel != 0.0)
    out += ": over the fitted stiffness, " + number_text(1e3 * f.as_travel) +
           " mm the specimen did not travel while the displacement read did, or a load cell that "
           "drifted";
  return out + "; a function of that line explains " + fixed_text(100.0 * f.of_response, 0) +
         " % of the re-run's error";
}

std::string windows_text(const std::vector<ResidualWindow>& windows) {
  if (windows.empty()) return "spread over the record";
  std::string out;
  for (std::size_t i = 0; i < windows.size(); ++i)
    out += (i ? ", " : "in ") + fixed_text(windows[i].start, 2) + "-" +
           fixed_text(windows[i].end, 2) + " s (" + fixed_text(100.0 * windows[i].share, 0) + " %)";
  return out;
}

// The displacement sensor the entry is on: the first force channel's with the slow part.
std::string candidate(const ResponseFloor& f) {
  return "displacement sensor " + std::to_string(f.force.empty() ? 1 : f.force.front().actuator);
}

}  // namespace

std::string ResponseFloor::text() const {
  std::string out = "the re-run's response: the identified re-run leaves " + percent_text(error) +
                    " (worst floor, DOF " + std::to_string(dof) + "), " +
                    fixed_text(error / floor, 1) + " x its floor " + percent_text(floor) +
                    " (the load cells' white noise propagated through the re-run " +
                    percent_text(noise_floor) + ", at least " + percent_text(kMinResponseFloor) +
                    "; above is over " + fixed_text(kResponseFloorFactor, 0) + " x)";
  if (!above) return out + ": at its floor";
  out += "; " + windows_text(windows) + "; at " + fixed_text(band.peak_hz, 2) +
         " Hz (80 % of its power within " + fixed_text(band.low_hz, 2) + "-" +
         fixed_text(band.high_hz, 2) + " Hz); its RMS over the record's last quarter " +
         number_text(growth) + " x over its first";
  if (of_time >= kMinRelation)
    out += "; a slow trend: a function of time explains " + fixed_text(100.0 * of_time, 0) +
           " % of it";
  out += "; a function of the recorded displacement explains " +
         fixed_text(100.0 * of_displacement, 0) + " %";
  for (const ForceTrend& f : force) out += "; " + force_text(f);
  if (silent)
    out +=
        "; no channel explains it (every channel at its floor): a sensor the loop closes on is "
        "a candidate (" +
        candidate(*this) +
        "), since a transducer error that the loop follows is invisible on its own channel";
  return out;
}

nlohmann::json ResponseFloor::json() const {
  nlohmann::json w = nlohmann::json::array(), f = nlohmann::json::array();
  for (const auto& x : windows)
    w.push_back({{"start_s", x.start}, {"end_s", x.end}, {"share", x.share}});
  for (const auto& t : force)
    f.push_back({{"actuator", t.actuator},
                 {"change_n", t.change},
                 {"as_travel_m", t.as_travel},
                 {"explained", t.explained},
                 {"of_response", t.of_response}});
  return {{"error", error},
          {"floor", floor},
          {"noise_floor", noise_floor},
          {"min_floor", kMinResponseFloor},
          {"factor", kResponseFloorFactor},
          {"above", above},
          {"dof", dof},
          {"windows", w},
          {"peak_hz", above ? nlohmann::json(band.peak_hz) : nlohmann::json()},
          {"band_hz", above ? nlohmann::json{band.low_hz, band.high_hz} : nlohmann::json()},
          {"growth", growth},
          {"of_time", of_time},
          {"of_displacement", of_displacement},
          {"force", f},
          {"silent", silent},
          {"text", text()}};
}

nlohmann::json ResponseFloor::unexplained_json() const {
  if (!above || !silent || force.empty()) return nullptr;
  nlohmann::json when = nlohmann::json::array();
  for (const auto& x : windows)
    when.push_back(
        {{"kind", "response error"}, {"start_s", x.start}, {"end_s", x.end}, {"share", x.share}});
  return {{"part", candidate(*this)},
          {"channel", "response"},
          {"share_pct", nullptr},
          {"kinds", nlohmann::json::array({"time_varying"})},
          {"when", when},
          {"text", text()}};
}

}  // namespace rths::identify
