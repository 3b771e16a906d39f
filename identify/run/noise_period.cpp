#include "identify/run/noise_period.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "identify/fit/effect_parameters.h"
#include "identify/model/signals.h"
#include "identify/run/sensors.h"

namespace rths::identify {
namespace {

// The model's input band (Hz, noise_period.h): the force channel's input cutoff; 0 without one.
double input_band(const ActuatorPath& path) {
  return path.id.find(Channel::kForce) ? identified_signals(path.id, Channel::kForce).input_cutoff
                                       : 0.0;
}

}  // namespace

std::optional<Unexplained> period_in_noise_band(const ActuatorPath& path, Channel channel) {
  const double band = input_band(path);
  if (!path.id.find(channel) || !(band > 0.0)) return std::nullopt;
  const ChannelSignals& s = identified_signals(path.id, channel);
  if (s.size() < 2 * kDescriptionWindows * kMapBins || !(band < 0.5 / s.dt)) return std::nullopt;
  const std::vector<double> p = prediction_without(path, channel, not_named_on(path, channel));
  const std::vector<double> r = minus(s.target, p);
  const std::vector<double> above = minus(r, zero_phase_lowpass(r, s.dt, band));
  ResidualDescription d = describe_residual(s.time, above, p, s.dt);
  if (!d.periodic || d.kinds().size() != 1 || !(d.periodic->frequency > band)) return std::nullopt;
  const bool force = channel == Channel::kForce;
  Unexplained u;
  u.actuator = path.actuator;
  u.channel = channel;
  u.part = (force ? "load cell " : "displacement sensor ") + std::to_string(path.actuator);
  u.channel_word = force ? "force" : "displacement";
  u.unit = force ? "N" : "m";
  u.time = s.time;
  const double with = white_noise(r), without = white_noise(minus(r, d.described));
  u.notes.push_back("a period in the residual above the model's " + fixed_text(band, 1) +
                    " Hz input band, what the noise estimate is made of: the sensor's noise " +
                    number_text(without) + " " + u.unit + " RMS without it (" + number_text(with) +
                    " " + u.unit + " RMS with it)");
  u.description = std::move(d);
  return u;
}

std::vector<Unexplained> describe_with_noise_periods(const ActuatorPath& path) {
  std::vector<Unexplained> out = describe_unexplained(path);
  // A period in a sensor's noise band (noise_period.h), where the channel's description holds
  // none and no channel of the path holds one at its frequency (a rod's ripple that the specimen
  // passes on to the load cell is the rod's).
  for (Channel channel : {Channel::kMeasured, Channel::kForce}) {
    const auto has_period = [&](const Unexplained& u) {
      return u.channel == channel && u.description.periodic;
    };
    if (std::any_of(out.begin(), out.end(), has_period)) continue;
    auto found = period_in_noise_band(path, channel);
    if (!found) continue;
    const double f = found->description.periodic->frequency;
    const auto same_period = [&](const Unexplained& u) {
      return u.description.periodic &&
             std::abs(u.description.periodic->frequency - f) <= kSamePeriod * f;
    };
    if (std::none_of(out.begin(), out.end(), same_period)) out.push_back(std::move(*found));
  }
  return out;
}

}  // namespace rths::identify
