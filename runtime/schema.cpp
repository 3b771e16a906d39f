#include "runtime/schema.h"

namespace rths::runtime {

transport::Message pack(const std::string& run_id, std::int32_t node_id, MessageKind kind,
                        std::int64_t step, const google::protobuf::MessageLite& payload) {
  transport::Message m;
  m.run_id = run_id;
  m.node_id = node_id;
  m.kind = kind;
  m.step = step;
  payload.SerializeToString(&m.payload);
  return m;
}

std::string kind_name(std::int32_t kind) {
  if (MessageKind_IsValid(kind)) return MessageKind_Name(static_cast<MessageKind>(kind));
  return "kind " + std::to_string(kind);
}

std::string node_kind_name(config::NodeSpec::Kind kind) {
  switch (kind) {
    case config::NodeSpec::SUBSTRUCTURE: return "substructure";
    case config::NodeSpec::ACTUATOR_EMULATOR: return "actuator emulator";
    default: return "unspecified";
  }
}

}  // namespace rths::runtime
