#include "identify/model/effects.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace rths::identify {
namespace {

struct EffectInfo {
  Effect effect;
  const char* name;
  bool measured, force;
};

constexpr std::array<EffectInfo, 17> kEffects{{
    {Effect::kDelay, "delay", true, true},
    {Effect::kOffsetDrift, "offset_drift", true, true},
    {Effect::kFirstOrder, "first_order", true, false},
    {Effect::kSecondOrder, "second_order", true, false},
    {Effect::kBacklash, "backlash", true, false},
    {Effect::kVelocitySaturation, "velocity_saturation", true, false},
    {Effect::kStrokeLimit, "stroke_limit", true, false},
    {Effect::kTimeVaryingDelay, "time_varying_delay", true, false},
    {Effect::kTimeVaryingGain, "time_varying_gain", true, false},
    {Effect::kStiffness, "stiffness", false, true},
    {Effect::kDamping, "damping", false, true},
    {Effect::kCoulomb, "coulomb_friction", false, true},
    {Effect::kBoucWen, "bouc_wen", false, true},
    {Effect::kCubicStiffness, "cubic_stiffness", false, true},
    {Effect::kTimeVaryingStiffness, "time_varying_stiffness", false, true},
    {Effect::kInertia, "inertia", false, true},
    {Effect::kElastoPlastic, "elastoplastic", false, true},
}};

const EffectInfo& info(Effect effect) {
  for (const auto& e : kEffects) {
    if (e.effect == effect) return e;
  }
  throw std::logic_error("effect without info");
}

}  // namespace

std::string channel_name(Channel channel) {
  return channel == Channel::kMeasured ? "measured" : "force";
}

std::string effect_name(Effect effect) { return info(effect).name; }

Effect parse_effect(const std::string& name) {
  for (const auto& e : kEffects) {
    if (name == e.name) return e.effect;
  }
  std::string names;
  for (const auto& e : kEffects) names += (names.empty() ? "" : ", ") + std::string(e.name);
  throw std::invalid_argument("unknown effect '" + name + "' (known: " + names + ")");
}

bool effect_applies(Effect effect, Channel channel) {
  const auto& e = info(effect);
  return channel == Channel::kMeasured ? e.measured : e.force;
}

std::vector<Effect> effect_library(Channel channel) {
  std::vector<Effect> out;
  for (const auto& e : kEffects) {
    if (effect_applies(e.effect, channel)) out.push_back(e.effect);
  }
  return out;
}

}  // namespace rths::identify
