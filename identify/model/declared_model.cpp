#include "identify/model/declared_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "study/text_format.h"

namespace rths::identify {
namespace {

std::string number(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

[[noreturn]] void fail(const std::string& source, const std::string& field,
                       const std::string& message) {
  throw std::invalid_argument(source + ": " + field + ": " + message);
}

Effect channel_effect(const std::string& name, Channel channel, const std::string& source,
                      const std::string& field) {
  Effect effect{};
  try {
    effect = parse_effect(name);
  } catch (const std::invalid_argument& e) {
    fail(source, field, e.what());
  }
  if (!effect_applies(effect, channel)) {
    fail(source, field,
         "effect '" + name + "' does not apply to channel '" + channel_name(channel) + "'");
  }
  return effect;
}

void add_effect(std::vector<Effect>& effects, Effect effect, const std::string& source,
                const std::string& field) {
  if (std::find(effects.begin(), effects.end(), effect) != effects.end()) {
    fail(source, field, "effect '" + effect_name(effect) + "' is declared twice");
  }
  effects.push_back(effect);
}

// Names of the parameters of a channel model with these effects (names do not depend on scales).
std::vector<std::string> parameter_names(Channel channel, const std::vector<Effect>& effects) {
  ChannelModel model;
  model.channel = channel;
  model.effects = effects;
  std::vector<std::string> names;
  for (const auto& spec : model.specs(SignalScales{})) names.push_back(spec.name);
  return names;
}

std::vector<ParamDeclaration> read_parameters(
    const google::protobuf::RepeatedPtrField<config::ParameterDeclaration>& parameters,
    Channel channel, const std::vector<Effect>& effects, const std::string& source,
    const std::string& prefix) {
  const auto known = parameter_names(channel, effects);
  std::vector<ParamDeclaration> out;
  for (int i = 0; i < parameters.size(); ++i) {
    const auto& p = parameters[i];
    const std::string field = prefix + ".parameters[" + std::to_string(i) + "]" +
                              (p.name().empty() ? "" : " (" + p.name() + ")");
    if (p.name().empty()) fail(source, field, "no name");
    if (std::find(known.begin(), known.end(), p.name()) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      fail(source, field,
           "unknown parameter '" + p.name() + "' for the declared " + prefix +
               " (its parameters: " + (list.empty() ? "none" : list) + ")");
    }
    for (const auto& earlier : out) {
      if (earlier.name == p.name()) fail(source, field, "parameter declared twice");
    }
    ParamDeclaration d;
    d.name = p.name();
    d.fixed = p.fixed();
    if (p.has_initial()) d.initial = p.initial();
    if (p.has_min()) d.lower = p.min();
    if (p.has_max()) d.upper = p.max();
    for (const auto& [what, value] :
         {std::pair{"initial", d.initial}, std::pair{"min", d.lower}, std::pair{"max", d.upper}}) {
      if (value && !std::isfinite(*value))
        fail(source, field, std::string(what) + " is not finite");
    }
    if (d.lower && d.upper && *d.lower > *d.upper) {
      fail(source, field, "min " + number(*d.lower) + " > max " + number(*d.upper));
    }
    if (d.initial && d.lower && *d.initial < *d.lower) {
      fail(source, field, "initial " + number(*d.initial) + " is below min " + number(*d.lower));
    }
    if (d.initial && d.upper && *d.initial > *d.upper) {
      fail(source, field, "initial " + number(*d.initial) + " is above max " + number(*d.upper));
    }
    if (d.fixed && !d.initial) fail(source, field, "fixed needs an initial value to hold");
    out.push_back(d);
  }
  return out;
}

void add_parameters(google::protobuf::RepeatedPtrField<config::ParameterDeclaration>& out,
                    const ChannelModel& model) {
  const auto specs = model.specs(SignalScales{});
  for (std::size_t i = 0; i < specs.size(); ++i) {
    auto* p = out.Add();
    p->set_name(specs[i].name);
    p->set_initial(model.params.at(i));
    for (const auto& d : model.declarations) {
      if (d.name != specs[i].name) continue;
      if (d.lower) p->set_min(*d.lower);
      if (d.upper) p->set_max(*d.upper);
      p->set_fixed(d.fixed);
    }
    // A fitted value can sit a rounding error outside a declared bound: keep the file readable.
    if (p->has_min()) p->set_initial(std::max(p->initial(), p->min()));
    if (p->has_max()) p->set_initial(std::min(p->initial(), p->max()));
  }
}

}  // namespace

DeclaredModel parse_declared_model(const std::string& text, const std::string& source) {
  config::DeclaredModel proto;
  study::parse_text_format(text, source, proto);
  DeclaredModel out;
  out.source = source;
  if (proto.has_actuator()) {
    DeclaredChannel actuator;
    const auto& a = proto.actuator();
    for (int i = 0; i < a.stages_size(); ++i) {
      const std::string field = "actuator.stages[" + std::to_string(i) + "]";
      add_effect(actuator.effects, channel_effect(a.stages(i), Channel::kMeasured, source, field),
                 source, field);
    }
    actuator.parameters =
        read_parameters(a.parameters(), Channel::kMeasured, actuator.effects, source, "actuator");
    out.actuator = std::move(actuator);
  }
  if (proto.has_specimen()) {
    DeclaredChannel specimen;
    const auto& s = proto.specimen();
    if (!s.kind().empty()) {
      try {
        specimen.kind = parse_kind(s.kind());
      } catch (const std::invalid_argument& e) {
        fail(source, "specimen.kind", e.what());
      }
      specimen.effects = kind_effects(*specimen.kind);
    }
    for (int i = 0; i < s.effects_size(); ++i) {
      const std::string field = "specimen.effects[" + std::to_string(i) + "]";
      const Effect e = channel_effect(s.effects(i), Channel::kForce, source, field);
      if (specimen.kind && std::find(specimen.effects.begin(), specimen.effects.end(), e) !=
                               specimen.effects.end()) {
        fail(source, field,
             "effect '" + s.effects(i) + "' is already part of kind '" + s.kind() + "'");
      }
      add_effect(specimen.effects, e, source, field);
    }
    specimen.parameters =
        read_parameters(s.parameters(), Channel::kForce, specimen.effects, source, "specimen");
    out.specimen = std::move(specimen);
  }
  return out;
}

DeclaredModel load_declared_model(const std::filesystem::path& path) {
  return parse_declared_model(study::read_text_file(path, "declared model"), path.string());
}

void check_physical_bounds(const DeclaredChannel& declared, Channel channel,
                           const SignalScales& scales, const std::string& source) {
  ChannelModel model;
  model.channel = channel;
  model.effects = declared.effects;
  const auto physical = model.specs(scales);  // no declarations: the library's bounds
  const std::string prefix = channel == Channel::kMeasured ? "actuator" : "specimen";
  for (std::size_t i = 0; i < declared.parameters.size(); ++i) {
    const auto& d = declared.parameters[i];
    const auto spec = std::find_if(physical.begin(), physical.end(),
                                   [&](const ParamSpec& s) { return s.name == d.name; });
    if (spec == physical.end()) continue;  // parse_declared_model refused unknown names
    const std::string field = prefix + ".parameters[" + std::to_string(i) + "] (" + d.name + ")";
    const std::string unit = " " + spec->unit;
    for (const auto& [what, value] :
         {std::pair{"min", d.lower}, std::pair{"max", d.upper}, std::pair{"initial", d.initial}}) {
      if (!value) continue;
      if (*value < spec->lower) {
        fail(source, field,
             std::string(what) + " " + number(*value) + unit + " is below the physical bound " +
                 number(spec->lower) + unit +
                 (spec->below_means.empty() ? "" : " (it would be " + spec->below_means + ")"));
      }
      if (*value > spec->upper) {
        fail(source, field,
             std::string(what) + " " + number(*value) + unit + " is above the physical bound " +
                 number(spec->upper) + unit + " for this record");
      }
    }
  }
}

config::DeclaredModel to_config(const ChannelModel* actuator, const ChannelModel* specimen) {
  config::DeclaredModel out;
  if (actuator != nullptr) {
    auto* a = out.mutable_actuator();
    for (Effect e : actuator->effects) a->add_stages(effect_name(e));
    add_parameters(*a->mutable_parameters(), *actuator);
  }
  if (specimen != nullptr) {
    auto* s = out.mutable_specimen();
    std::optional<SpecimenKind> best;
    std::size_t best_size = 0;
    for (SpecimenKind kind : specimen_kinds()) {
      const auto effects = kind_effects(kind);
      const bool contained =
          std::all_of(effects.begin(), effects.end(), [&](Effect e) { return specimen->has(e); });
      if (contained && effects.size() > best_size) {
        best = kind;
        best_size = effects.size();
      }
    }
    std::vector<Effect> of_kind;
    if (best) {
      s->set_kind(kind_name(*best));
      of_kind = kind_effects(*best);
    }
    for (Effect e : specimen->effects) {
      if (std::find(of_kind.begin(), of_kind.end(), e) == of_kind.end()) {
        s->add_effects(effect_name(e));
      }
    }
    add_parameters(*s->mutable_parameters(), *specimen);
  }
  return out;
}

}  // namespace rths::identify
