#include "identify/fit/effect_parameters.h"

#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace rths::identify {

std::string ParameterEstimate::describe() const {
  // Lab-sized quantities in SI would read 0.008 s or 0.0004 m: milli-units read 8 ms, 0.4 mm.
  const bool milli = unit == "s" || unit == "m" || unit == "m/s";
  const double scale = milli ? 1e3 : 1.0;
  const std::string shown = milli ? "m" + unit : unit;
  // A ratio's unit ("-") is not written.
  const std::string suffix = unit == "-" || unit.empty() ? "" : " " + shown;
  std::ostringstream out;
  out << std::setprecision(3) << name << " = " << value * scale << suffix << " +/- "
      << std_error * scale << suffix;
  return out.str();
}

std::vector<ParameterEstimate> effect_parameters(const FitResult& fit, Effect effect,
                                                 const SignalScales& scales) {
  std::vector<ParameterEstimate> out;
  std::size_t index = base_params(fit.model.channel, scales).size();
  for (Effect e : fit.model.effects) {
    const auto specs = effect_params(e, fit.model.channel, scales);
    for (std::size_t i = 0; e == effect && i < specs.size(); ++i) {
      const std::size_t at = index + i;
      out.push_back({specs[i].name, specs[i].unit, fit.model.params.at(at),
                     at < fit.std_errors.size() ? fit.std_errors[at] : 0.0});
    }
    index += specs.size();
  }
  return out;
}

const ChannelSignals& identified_signals(const Identification& id, Channel channel) {
  for (const auto& s : id.signals)
    if (s.channel == channel) return s;
  throw std::invalid_argument("no signals for channel " + channel_name(channel));
}

}  // namespace rths::identify
