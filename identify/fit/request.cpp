#include "identify/fit/request.h"

#include <optional>
#include <stdexcept>

#include "study/ranges.h"

namespace rths::identify {
namespace {

constexpr std::size_t kMaxSteps = 1000;
constexpr const char* kNoEffect = "none";  // a list of no effect, as a user writes it

std::vector<Effect> parse_effects(const std::vector<std::string>& names,
                                  std::optional<Channel> channel, const std::string& argument) {
  std::vector<Effect> out;
  for (const auto& name : names) {
    if (name.empty() || name == kNoEffect) continue;
    const Effect effect = parse_effect(name);
    if (channel && !effect_applies(effect, *channel))
      throw std::invalid_argument(argument + ": effect '" + name + "' does not apply to channel '" +
                                  channel_name(*channel) + "'");
    out.push_back(effect);
  }
  return out;
}

std::vector<Channel> parse_channels(const std::vector<std::string>& names,
                                    const std::string& argument) {
  std::vector<Channel> out;
  for (const auto& name : names) {
    if (name == channel_name(Channel::kMeasured))
      out.push_back(Channel::kMeasured);
    else if (name == channel_name(Channel::kForce))
      out.push_back(Channel::kForce);
    else
      throw std::invalid_argument(argument + ": unknown channel '" + name + "' (measured, force)");
  }
  if (out.empty()) throw std::invalid_argument(argument + ": no channel given");
  return out;
}

}  // namespace

IdentifyOptions identify_options(const IdentifyRequest& request, const ArgumentName& argument) {
  study::check_range(study::Quantity::kFraction, request.holdout, argument("holdout"));
  if (request.max_steps > kMaxSteps)
    throw std::invalid_argument(argument("max_steps") + " = " + std::to_string(request.max_steps) +
                                " is outside [0, " + std::to_string(kMaxSteps) + "]");
  IdentifyOptions options;
  options.channels = parse_channels(request.channels, argument("channels"));
  options.declared_actuator =
      parse_effects(request.declared_actuator, Channel::kMeasured, argument("declared_actuator"));
  options.declared_specimen =
      parse_effects(request.declared_specimen, Channel::kForce, argument("declared_specimen"));
  options.selection.candidates =
      parse_effects(request.candidates, std::nullopt, argument("candidates"));
  options.holdout_fraction = request.holdout;
  options.holdout_mode = parse_holdout_mode(request.holdout_mode);
  options.holdout_blocks = request.holdout_blocks;
  options.search_decimation = request.search_decimation;
  options.search_samples = request.search_samples;
  options.search_tolerance = request.search_tolerance;
  options.search_iterations = request.search_iterations;
  options.selection.min_relative_improvement = request.min_improvement;
  options.selection.penalty_per_parameter = request.penalty;
  options.selection.max_steps = request.max_steps;
  return options;
}

}  // namespace rths::identify
