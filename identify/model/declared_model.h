#pragma once
// The declared model as a config file (proto/identify.proto, text format like the studies):
// reading and checking it, and writing an identified model back in the same form, so that
// `rths identify DATA --out DIR` followed by `rths identify DATA2 --model DIR/identified_model.textproto`
// starts the second identification where the first ended.
//
// Checks on reading (std::invalid_argument "FILE: FIELD: message", the CLI's exit 2):
//   syntax, unknown fields and wrong types (study/text_format.h, with line and column);
//   an unknown stage, kind or effect, one that does not apply to its channel, or one given twice;
//   a parameter name that is not one of the channel model's (listed), or given twice;
//   a non-finite value, min > max, initial outside [min, max], fixed without an initial value.
// Checks against the record (check_physical_bounds), once its scales are known: a declared min,
// max or initial beyond the library's physical bound (model.h), e.g. a negative stiffness or a
// delay longer than half the record.
// Writing: every parameter of the model with its fitted value as `initial`; declared bounds and
// fixed flags are carried over; the specimen's kind is the library kind with the most of the
// model's effects (specimen.h), the other effects are listed beside it.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "identify/model/model.h"
#include "identify/model/specimen.h"
#include "rths/proto/identify.pb.h"

namespace rths::identify {

struct DeclaredChannel {
  std::vector<Effect> effects;  // in the model's order (a specimen kind's effects first)
  std::vector<ParamDeclaration> parameters;
  std::optional<SpecimenKind> kind;  // specimen only
};

struct DeclaredModel {
  std::string source;  // file name, for messages
  std::optional<DeclaredChannel> actuator, specimen;
};

DeclaredModel parse_declared_model(const std::string& text, const std::string& source);
DeclaredModel load_declared_model(const std::filesystem::path& path);

// Throws std::invalid_argument naming the source and the field when a declared value lies beyond
// the channel's physical bounds at these signal scales (model.h effect_params).
void check_physical_bounds(const DeclaredChannel& declared, Channel channel,
                           const SignalScales& scales, const std::string& source);

// The identified models (either may be null) as a declared-model config (written with
// study::write_text_format).
config::DeclaredModel to_config(const ChannelModel* actuator, const ChannelModel* specimen);

}  // namespace rths::identify
