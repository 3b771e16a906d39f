#pragma once
// The catalogue of effects identification may find: the two measured channels, every effect by
// name, which channel each applies to. Their equations are in model.h, their parameters in
// parameters.h.

#include <cstddef>
#include <string>
#include <vector>

namespace rths::identify {

enum class Channel { kMeasured, kForce };
std::string channel_name(Channel channel);

enum class Effect {
  // either channel
  kDelay,        // constant delay (actuator lag, or force lagging displacement)
  kOffsetDrift,  // constant offset + linear drift
  // actuator (channel measured)
  kFirstOrder,
  kSecondOrder,
  kBacklash,
  kVelocitySaturation,
  kStrokeLimit,
  kTimeVaryingDelay,
  kTimeVaryingGain,
  // specimen (channel force)
  kStiffness,
  kDamping,
  kCoulomb,
  kBoucWen,
  kCubicStiffness,
  kTimeVaryingStiffness,
  kInertia,
  kElastoPlastic,
};

// Number of cosine terms of every slow drift D(s; c).
inline constexpr std::size_t kDriftTerms = 8;

std::string effect_name(Effect effect);
// Inverse of effect_name ("delay", "first_order", ...). Throws std::invalid_argument.
Effect parse_effect(const std::string& name);
bool effect_applies(Effect effect, Channel channel);
// Every effect of the library that applies to the channel, in a fixed order.
std::vector<Effect> effect_library(Channel channel);

}  // namespace rths::identify
