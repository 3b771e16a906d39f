#include "identify/model/specimen.h"

#include <algorithm>
#include <array>
#include <stdexcept>

namespace rths::identify {
namespace {

struct KindInfo {
  SpecimenKind kind;
  const char* name;
  std::vector<Effect> effects, defining;
  bool hysteretic_damper;
};

const std::array<KindInfo, 6>& kinds() {
  static const std::array<KindInfo, 6> table{{
      {SpecimenKind::kLinearSpring,
       "linear_spring",
       {Effect::kStiffness},
       {Effect::kStiffness},
       false},
      {SpecimenKind::kViscousDamper,
       "viscous_damper",
       {Effect::kDamping},
       {Effect::kDamping},
       false},
      {SpecimenKind::kBoucWen,
       "bouc_wen",
       {Effect::kStiffness, Effect::kBoucWen},
       {Effect::kBoucWen},
       false},
      {SpecimenKind::kMrDamper,
       "mr_damper",
       {Effect::kStiffness, Effect::kDamping, Effect::kBoucWen},
       {Effect::kDamping, Effect::kBoucWen},
       true},
      {SpecimenKind::kBilinear,
       "bilinear",
       {Effect::kStiffness, Effect::kElastoPlastic},
       {Effect::kElastoPlastic},
       false},
      {SpecimenKind::kFriction, "friction", {Effect::kCoulomb}, {Effect::kCoulomb}, false},
  }};
  return table;
}

const KindInfo& info(SpecimenKind kind) {
  for (const auto& k : kinds()) {
    if (k.kind == kind) return k;
  }
  throw std::logic_error("specimen kind without info");
}

}  // namespace

std::string kind_name(SpecimenKind kind) { return info(kind).name; }

SpecimenKind parse_kind(const std::string& name) {
  std::string names;
  for (const auto& k : kinds()) {
    if (name == k.name) return k.kind;
    names += (names.empty() ? "" : ", ") + std::string(k.name);
  }
  throw std::invalid_argument("unknown specimen kind '" + name + "' (known: " + names + ")");
}

std::vector<SpecimenKind> specimen_kinds() {
  std::vector<SpecimenKind> out;
  for (const auto& k : kinds()) out.push_back(k.kind);
  return out;
}

std::vector<Effect> kind_effects(SpecimenKind kind) { return info(kind).effects; }

std::vector<Effect> defining_effects(SpecimenKind kind) { return info(kind).defining; }

bool is_hysteretic_damper(SpecimenKind kind) { return info(kind).hysteretic_damper; }

std::optional<SpecimenKind> kind_of(const std::vector<Effect>& effects) {
  auto sorted = effects;
  std::sort(sorted.begin(), sorted.end());
  for (const auto& k : kinds()) {
    auto mine = k.effects;
    std::sort(mine.begin(), mine.end());
    if (mine == sorted) return k.kind;
  }
  return std::nullopt;
}

}  // namespace rths::identify
