#pragma once
// Shared by the controller tests: one actuator's frames, as a lab would lay them out, in config
// text (config::ControllerLink), on 127.0.0.1 at the given ports.
//   command  (32 bytes): counter u32, status u32, time f64, target f64, target velocity f64
//   feedback (24 bytes): counter u32 (echo), status i32, measured drift f64, measured force f64
// All little endian at scale 1, so doubles cross unchanged.

#include <google/protobuf/text_format.h>

#include <stdexcept>
#include <string>

#include "rths/proto/deployment.pb.h"

namespace rths::test {

inline constexpr const char* kCommandFields =
    "command { fields { name: \"counter\" role: COUNTER type: U32 } "
    "fields { name: \"status\" role: STATUS type: U32 } "
    "fields { name: \"time\" role: COMMAND_TIME unit: \"s\" } "
    "fields { name: \"target\" role: TARGET_DISPLACEMENT unit: \"m\" } "
    "fields { name: \"velocity\" role: TARGET_VELOCITY unit: \"m/s\" } }";
inline constexpr const char* kFeedbackFields =
    "feedback { fields { name: \"counter\" role: COUNTER type: U32 } "
    "fields { name: \"status\" role: STATUS type: I32 } "
    "fields { name: \"measured\" role: MEASURED_DISPLACEMENT unit: \"m\" } "
    "fields { name: \"force\" role: MEASURED_FORCE unit: \"N\" } }";

// The link's config text: the node binds 127.0.0.1:node_port, the controller 127.0.0.1:peer_port.
inline std::string controller_link_text(int node_port, int peer_port,
                                        const std::string& extra = "") {
  return "local_address: \"127.0.0.1\" local_port: " + std::to_string(node_port) +
         " peer_address: \"127.0.0.1\" peer_port: " + std::to_string(peer_port) + " " +
         kCommandFields + " " + kFeedbackFields + " " + extra;
}

inline config::ControllerLink controller_link(int node_port, int peer_port,
                                              const std::string& extra = "") {
  config::ControllerLink link;
  if (!google::protobuf::TextFormat::ParseFromString(
          controller_link_text(node_port, peer_port, extra), &link))
    throw std::invalid_argument("bad controller link text");
  return link;
}

}  // namespace rths::test
