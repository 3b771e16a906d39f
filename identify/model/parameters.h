#pragma once
// The parameter layout of a channel model: each effect's parameters with units, scales, bounds
// and first guesses; a declared model's word on them; and the model as effects plus values.

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "identify/model/effects.h"
#include "identify/model/signals.h"

namespace rths::identify {

struct ParamSpec {
  std::string name, unit;
  double scale = 1.0;  // typical magnitude, so that value / scale is O(1) for the fit
  double lower = -1e300, upper = 1e300;
  std::vector<double> guesses;  // starting values tried when the effect is added
  // What a value below `lower` would mean physically ("a negative stiffness"); empty when the
  // lower bound is numerical only.
  std::string below_means;
  // Offsets, drifts and drift coefficients belong to one record: re-estimated, not carried over,
  // when a model is validated on another record.
  bool record_specific = false;
  // Held at its value by every fit (a declared model's `fixed`, see ParamDeclaration).
  bool fixed = false;
};

// What a declared model (proto/identify.proto, identify/model/declared_model.h) says of one
// parameter, keyed by its name (parameter names are unique within a channel):
//   initial  replaces the library's starting guesses;
//   lower / upper narrow the physical bounds (max(physical, declared), min(...)), never widen them;
//   fixed    holds the parameter at its value in every fit.
// A declaration whose name is not in the model has no effect (it applies once the effect is added).
struct ParamDeclaration {
  std::string name;
  std::optional<double> initial, lower, upper;
  bool fixed = false;
};

// `specs` with the declarations of the same names applied. When a declared lower bound is above
// the physical one, the bound hit is about the declared bound, so below_means is cleared.
std::vector<ParamSpec> declared_specs(std::vector<ParamSpec> specs,
                                      const std::vector<ParamDeclaration>& declarations);

// The parameters an effect adds (in order). Base parameters of a channel: `gain` for measured,
// none for force.
std::vector<ParamSpec> effect_params(Effect effect, Channel channel, const SignalScales& scales);
std::vector<ParamSpec> base_params(Channel channel, const SignalScales& scales);

struct ChannelModel {
  Channel channel = Channel::kMeasured;
  std::vector<Effect> effects;  // in the order they were added
  std::vector<double> params;   // base params, then each effect's params in `effects` order
  // Parameters held at their value by the fit (same indexing as params; missing = free).
  std::vector<bool> fixed;
  // The declared model's word on parameters (by name); specs() applies them, so every fit,
  // k-fold and validation of this model and of the models grown from it respects them.
  std::vector<ParamDeclaration> declarations;

  bool has(Effect effect) const;
  bool is_fixed(std::size_t index) const { return index < fixed.size() && fixed[index]; }
  // Index of the named parameter of `effect` (or of the base when effect is empty) in params.
  std::optional<std::size_t> index_of(std::optional<Effect> effect, const std::string& name,
                                      const SignalScales& scales) const;
  // The effect that owns parameter `index` (empty for a base parameter).
  std::optional<Effect> effect_of(std::size_t index, const SignalScales& scales) const;
  // Library specs of base and effects, with `declarations` applied; a spec is `fixed` when its
  // declaration or this model's `fixed` holds it: the one place a fit asks.
  std::vector<ParamSpec> specs(const SignalScales& scales) const;
  // The value of the named parameter of `effect` (or of the base when effect is empty).
  std::optional<double> param(std::optional<Effect> effect, const std::string& name,
                              const SignalScales& scales) const;
  std::string describe(const SignalScales& scales) const;
};

// The declared model with neutral parameter values (gain 1, delay 0, stiffness 0).
ChannelModel declared_model(Channel channel, const std::vector<Effect>& effects,
                            const SignalScales& scales);
// `model` with `effect` appended, its params set to `guess` (one per ParamSpec).
ChannelModel with_effect(const ChannelModel& model, Effect effect, std::span<const double> guess);
// `model` without `effect` and its params. Throws std::invalid_argument when it is absent.
ChannelModel without_effect(const ChannelModel& model, Effect effect, const SignalScales& scales);

}  // namespace rths::identify
