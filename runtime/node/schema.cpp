#include "runtime/node/schema.h"

namespace rths::runtime {

transport::Message pack(const std::string& run_id, std::int32_t node_id, MessageKind kind,
                        std::int64_t step, const google::protobuf::MessageLite& payload) {
  transport::Message m;
  pack_into(m, run_id, node_id, kind, step, payload);
  return m;
}

void pack_into(transport::Message& m, const std::string& run_id, std::int32_t node_id,
               MessageKind kind, std::int64_t step, const google::protobuf::MessageLite& payload) {
  m.run_id.assign(run_id);
  m.node_id = node_id;
  m.kind = kind;
  m.step = step;
  m.sent_ns = m.echo_ns = m.received_ns = 0;
  // As if carried on the node's own topic, from no known writer; a transport stamps the real
  // ones on receipt.
  m.topic_node = node_id;
  m.writer = 0;
  payload.SerializeToString(&m.payload);  // clears, keeps the capacity
}

std::string kind_name(std::int32_t kind) {
  if (MessageKind_IsValid(kind)) return MessageKind_Name(static_cast<MessageKind>(kind));
  return "kind " + std::to_string(kind);
}

std::string node_kind_name(config::NodeSpec::Kind kind) {
  switch (kind) {
    case config::NodeSpec::SUBSTRUCTURE: return "substructure";
    case config::NodeSpec::ACTUATOR_EMULATOR: return "actuator emulator";
    case config::NodeSpec::CONTROLLER: return "controller";
    default: return "unspecified";
  }
}

}  // namespace rths::runtime
