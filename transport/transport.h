#pragma once
// The transport the coordinator and the nodes talk to. A Message is one envelope: who, what kind,
// which step, two wall-clock stamps and an opaque Protobuf payload. Two directions exist:
//   down  coordinator -> node   (node_id = addressee)
//   up    node -> coordinator   (node_id = sender)
// Implementations: InProcessTransport (function calls, deterministic, no threads) and
// DdsEndpoint (Cyclone DDS, processes on any host). The same run gives the same numbers on both.
// Who may say what: every node has its own topic each way, so a receiver knows which node's
// topic carried a message (topic_node) and which writer sent it (writer); the envelope's node_id
// is only a claim, checked against both by the receiver (runtime/node/validation.h).
//
// Stamps are CLOCK_REALTIME nanoseconds (comparable across hosts up to their clock offset);
// round trips are measured on one host's clock from sent_ns and the echo, so carry no offset.

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace rths::transport {

struct Message {
  std::string run_id;
  std::int32_t node_id = 0;
  std::int32_t kind = 0;  // rths.runtime.MessageKind
  std::int64_t step = 0;
  std::int64_t sent_ns = 0;      // stamped by send() when 0
  std::int64_t echo_ns = 0;      // sent_ns of the message this answers
  std::string payload;           // Protobuf bytes
  std::int64_t received_ns = 0;  // stamped on receipt, never sent
  // Stamped on receipt, never sent: the node whose topic carried the message (its addressee on
  // the way down, its sender on the way up; kBroadcastId for the broadcast topic), and the
  // transport's identity of the writer that sent it (0 when the transport has none).
  std::int32_t topic_node = 0;
  std::uint64_t writer = 0;
};

// CLOCK_REALTIME now, ns.
std::int64_t realtime_ns();

class Endpoint {
 public:
  virtual ~Endpoint() = default;
  // Sends one message in this endpoint's direction. Throws std::runtime_error on failure.
  // Loop-thread contract: never waits for a peer (best-effort, no acknowledgement); may take a
  // short lock shared with the receive thread; allocates nothing in the DDS endpoint once the
  // addressed writer exists (the first message to a node creates it), and one queue entry in the
  // in-process one.
  virtual void send(const Message& message) = 0;
  // The next message addressed to this endpoint (nodes see only their own node id and
  // broadcasts to id -1), or nullopt when `timeout` passes or interrupt() is called.
  // Loop-thread contract: blocks up to `timeout` (0: a poll that never waits); the message
  // returned is moved out of the queue, so the caller owns its buffers (an allocation per queued
  // message, which is why feedback takes the inline handler instead).
  virtual std::optional<Message> receive(std::chrono::nanoseconds timeout) = 0;
  // Wakes a receive() blocked in another thread (thread safe).
  virtual void interrupt() = 0;
  // Number of remote endpoints currently matched to this one's writer.
  virtual int matched_peers() const = 0;
  // Coordinator: listen to node `node_id` on its own up topic (a node's messages arrive only
  // after this). Idempotent; transports that need no set-up ignore it.
  virtual void listen_to(std::int32_t node_id) { (void)node_id; }

  // Returns true when it consumed the message; false leaves it for receive().
  using InlineHandler = std::function<bool(const Message&)>;
  // Optional fast path: a transport with its own receive thread offers each arriving message to
  // `handler` on that thread first, which spares a thread wake-up per message (the handler must
  // be quick and thread safe against the caller's own use of its state). An empty handler
  // removes it; once this returns, no invocation of the old handler is in progress. Transports
  // without a receive thread ignore it and deliver everything through receive().
  virtual void set_inline_handler(InlineHandler handler) { (void)handler; }
};

inline constexpr std::int32_t kCoordinatorId = 0;
inline constexpr std::int32_t kBroadcastId = -1;

}  // namespace rths::transport
