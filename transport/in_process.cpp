#include "transport/in_process.h"

namespace rths::transport {

void InProcessTransport::attach(std::int32_t node_id, NodeHandler& handler) {
  nodes_[node_id] = &handler;
  for (Message& m : handler.start()) {
    m.received_ns = realtime_ns();
    m.topic_node = node_id;
    inbox_.push_back(std::move(m));
  }
}

void InProcessTransport::deliver(std::int32_t node_id, NodeHandler& handler,
                                 const Message& message) {
  for (Message& reply : handler.handle(message)) {
    if (reply.sent_ns == 0) reply.sent_ns = realtime_ns();
    reply.received_ns = realtime_ns();
    reply.topic_node = node_id;
    inbox_.push_back(std::move(reply));
  }
}

void InProcessTransport::send(const Message& message) {
  Message stamped = message;
  if (stamped.sent_ns == 0) stamped.sent_ns = realtime_ns();
  stamped.received_ns = stamped.sent_ns;
  stamped.topic_node = message.node_id;
  if (message.node_id == kBroadcastId) {
    // On each node's own topic, as DdsEndpoint writes a broadcast.
    for (auto& [id, handler] : nodes_) {
      stamped.topic_node = id;
      deliver(id, *handler, stamped);
    }
    return;
  }
  const auto it = nodes_.find(message.node_id);
  if (it != nodes_.end()) deliver(it->first, *it->second, stamped);
}

std::optional<Message> InProcessTransport::receive(std::chrono::nanoseconds) {
  if (inbox_.empty()) return std::nullopt;
  Message m = std::move(inbox_.front());
  inbox_.pop_front();
  return m;
}

}  // namespace rths::transport
