#pragma once
// MessageMac: HMAC-SHA256 of a message's meaning under the run secret (security/run_secret.h).
//
// Covered: a version tag, the direction (down: coordinator -> node, up: node -> coordinator, so
// a coordinator's message cannot be reflected as a node's), the DDS GUID of the writer that sends
// it, run id, node id, kind, step, sent_ns, echo_ns and the payload, each length-prefixed or fixed
// width. The sender signs with its own writer's GUID; the receiver verifies with the GUID of the
// writer the sample came from (its publication handle's, DdsEndpoint), so a genuine message
// re-published byte for byte by another participant's writer fails: a replay is dropped unread.
// Not covered: what the receiver stamps (received_ns, topic_node, writer: the instance handle,
// local to the receiver).
//
// sign() and verify() are thread safe without a lock: the HMAC's inner and outer SHA-256 states
// are computed once from the key and only copied per message (no allocation, no lock, four hash
// updates over the fields: about 0.2 us for a command with a warm cache; bench/mac_bench.cpp).
// verify() compares in constant time. The key is the secret's text (64 hex characters). The MAC
// is standard HMAC-SHA256 (RFC 2104) over the encoding above.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "transport/transport.h"

namespace rths::transport {

inline constexpr std::size_t kMacBytes = 32;
using Mac = std::array<std::uint8_t, kMacBytes>;

enum class Direction : std::uint8_t { kDown = 1, kUp = 2 };

// A DDS writer's GUID, 16 bytes as Cyclone gives it (dds_get_guid, the key of
// dds_get_matched_publication_data: the same bytes on both sides).
using WriterGuid = std::array<std::uint8_t, 16>;

// The covered fields, borrowed: a received sample is checked before it is copied into a Message,
// so a flood of forged messages costs the receive thread no copy and no allocation.
// `writer` is the sending writer's GUID (copied: 16 bytes).
struct MacInput {
  WriterGuid writer{};
  std::string_view run_id;
  std::int32_t node_id = 0, kind = 0;
  std::int64_t step = 0, sent_ns = 0, echo_ns = 0;
  std::string_view payload;
  static MacInput of(const Message& m, std::int64_t sent_ns, const WriterGuid& writer) {
    return {writer, m.run_id, m.node_id, m.kind, m.step, sent_ns, m.echo_ns, m.payload};
  }
};

class MessageMac {
 public:
  // @pre !key.empty().
  explicit MessageMac(const std::string& key);
  ~MessageMac();
  MessageMac(const MessageMac&) = delete;
  MessageMac& operator=(const MessageMac&) = delete;

  // The MAC of `message` sent in `direction` by the writer `writer`, stamped `sent_ns` on the
  // wire (send() stamps a message whose sent_ns is 0).
  Mac sign(const Message& message, std::int64_t sent_ns, Direction direction,
           const WriterGuid& writer) const;
  // Whether `mac` is the MAC of `message` received from `direction` off the writer `writer`.
  bool verify(const Message& message, const WriterGuid& writer, Direction direction,
              const Mac& mac) const;
  bool verify(const MacInput& fields, Direction direction, const Mac& mac) const;

 private:
  struct Context;
  std::unique_ptr<const Context> keyed_;
};

}  // namespace rths::transport
