#pragma once
// Packing Protobuf payloads into transport messages and back.
// pack():   (run id, node id, kind, step, payload) -> Message with serialized bytes (topic_node
//           = node id and writer 0, as a receiving transport stamps them for that node's topic).
// unpack(): Message -> payload; false when the bytes do not parse (counted as garbage).

#include <cstdint>
#include <string>

#include "rths/proto/runtime.pb.h"
#include "transport/transport.h"

namespace rths::runtime {

// Bumped on any incompatible change to runtime.proto / deployment.proto.
inline constexpr std::uint32_t kSchemaVersion = 1;

transport::Message pack(const std::string& run_id, std::int32_t node_id, MessageKind kind,
                        std::int64_t step, const google::protobuf::MessageLite& payload);

// The same into an existing message, reusing its strings' capacity: once warm, packing a payload
// no larger than before allocates nothing (the real-time loop's preallocated command message).
void pack_into(transport::Message& message, const std::string& run_id, std::int32_t node_id,
               MessageKind kind, std::int64_t step, const google::protobuf::MessageLite& payload);

template <class T>
bool unpack(const transport::Message& message, T& payload) {
  return payload.ParseFromString(message.payload);
}

std::string kind_name(std::int32_t kind);
std::string node_kind_name(config::NodeSpec::Kind kind);

// Whether a node of this kind drives the experimental storeys' actuators (an actuator emulator,
// or a lab's controller): it answers Command with realised drift and measured force, holds on
// HOLD and on its own watchdog. The coordinator treats both alike.
inline bool drives_actuators(config::NodeSpec::Kind kind) {
  return kind == config::NodeSpec::ACTUATOR_EMULATOR || kind == config::NodeSpec::CONTROLLER;
}

}  // namespace rths::runtime
