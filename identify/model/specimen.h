#pragma once
// The specimen library: the kinds of specimen a declared force model can be, each a set of the
// force channel's effects (model.h), and the comparison that proposes a better kind when the
// declared one is wrong.
//
//   linear_spring    F = k d
//   viscous_damper   F = c v
//   bouc_wen         F = k d + F_bw z                       (hysteretic spring)
//   mr_damper        F = k d + c v + F_bw z                 Bouc–Wen with viscous and spring: the
//                    Spencer et al. (1997) "simple Bouc–Wen" MR-damper model
//   bilinear         F = k d + p, p elasto-plastic          (k is the post-yield stiffness)
//   friction         F = F_c tanh(v / v_c)
// Every parameter carries its physical bound (model.h). A kind is wrong for the data when a
// parameter of its defining element (the spring of linear_spring, the dashpot of viscous_damper,
// the hysteresis of bouc_wen, bilinear and mr_damper and mr_damper's dashpot, the friction of
// friction) ends at a bound the data push against. A secondary spring at zero only says the
// specimen has no such spring; it is reported, not held against the kind.

#include <optional>
#include <string>
#include <vector>

#include "identify/model/model.h"

namespace rths::identify {

enum class SpecimenKind {
  kLinearSpring,
  kViscousDamper,
  kBoucWen,
  kMrDamper,
  kBilinear,
  kFriction
};

std::string kind_name(SpecimenKind kind);
// Inverse of kind_name. Throws std::invalid_argument listing the kinds.
SpecimenKind parse_kind(const std::string& name);
std::vector<SpecimenKind> specimen_kinds();
std::vector<Effect> kind_effects(SpecimenKind kind);
// The effects that make the kind what it is (a subset of kind_effects).
std::vector<Effect> defining_effects(SpecimenKind kind);
// A damper (its force follows the velocity) whose force also has hysteresis (a memory).
bool is_hysteretic_damper(SpecimenKind kind);
// The kind whose effects are exactly `effects` (any order), if there is one.
std::optional<SpecimenKind> kind_of(const std::vector<Effect>& effects);

}  // namespace rths::identify
