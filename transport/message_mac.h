#pragma once
// MessageMac: HMAC-SHA256 of a message's meaning under the run secret (security/run_secret.h).
//
// Covered: a version tag, the direction (down: coordinator -> node, up: node -> coordinator, so
// a coordinator's message cannot be reflected as a node's), run id, node id, kind, step, sent_ns,
// echo_ns and the payload, each length-prefixed or fixed width. Not covered: what the receiver
// stamps (received_ns, topic_node, writer).
//
// sign() and verify() are thread safe (one mutex each, so the loop's sends never wait for the
// receive thread's checks). Each reuses one OpenSSL MAC context keyed once: no allocation of
// ours per message; the cost is one HMAC over the message (about 1 us for a command). verify()
// compares in constant time. The key is the secret's text (64 hex characters).

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "transport/transport.h"

namespace rths::transport {

inline constexpr std::size_t kMacBytes = 32;
using Mac = std::array<std::uint8_t, kMacBytes>;

enum class Direction : std::uint8_t { kDown = 1, kUp = 2 };

class MessageMac {
 public:
  // @pre !key.empty(). Throws std::runtime_error when OpenSSL has no HMAC-SHA256.
  explicit MessageMac(const std::string& key);
  ~MessageMac();
  MessageMac(const MessageMac&) = delete;
  MessageMac& operator=(const MessageMac&) = delete;

  // The MAC of `message` sent in `direction`, stamped `sent_ns` on the wire (send() stamps a
  // message whose sent_ns is 0).
  Mac sign(const Message& message, std::int64_t sent_ns, Direction direction);
  // Whether `mac` is the MAC of `message` received from `direction`.
  bool verify(const Message& message, Direction direction, const Mac& mac);

 private:
  struct Context;
  std::unique_ptr<Context> signer_, verifier_;
  std::mutex sign_mutex_, verify_mutex_;
};

}  // namespace rths::transport
