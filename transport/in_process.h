#pragma once
// In-process transport: the coordinator's endpoint calls the nodes' handlers directly. No threads,
// no clocks involved in ordering: a down message is handled at once and the node's replies are
// queued for the coordinator's next receive(), stamped with the topic of the node that sent them
// (writer 0: no writer identity in process). Used for the in-process reference of a distributed
// configuration and for unit tests; the node logic is the same object a node process runs.

#include <deque>
#include <map>
#include <vector>

#include "transport/transport.h"

namespace rths::transport {

// What a node does with messages, independent of how they travel.
class NodeHandler {
 public:
  virtual ~NodeHandler() = default;
  // Messages the node sends on its own when it starts (its announcement).
  virtual std::vector<Message> start() = 0;
  // Replies to one message addressed to this node (or broadcast).
  virtual std::vector<Message> handle(const Message& message) = 0;
};

class InProcessTransport final : public Endpoint {
 public:
  // The handler must outlive the transport. Its start() messages are queued at once.
  void attach(std::int32_t node_id, NodeHandler& handler);
  void send(const Message& message) override;
  // Never blocks: every reply is already queued when send() returns.
  std::optional<Message> receive(std::chrono::nanoseconds timeout) override;
  void interrupt() override {}
  int matched_peers() const override { return static_cast<int>(nodes_.size()); }

 private:
  // Hands `message` to node `node_id`'s handler and queues its replies, stamped as from its topic.
  void deliver(std::int32_t node_id, NodeHandler& handler, const Message& message);
  std::map<std::int32_t, NodeHandler*> nodes_;
  std::deque<Message> inbox_;
};

}  // namespace rths::transport
