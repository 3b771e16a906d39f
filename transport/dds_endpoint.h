#pragma once
// Endpoint over Cyclone DDS. Two topics per domain: "rths_down" (coordinator -> nodes, keyed by
// the addressee) and "rths_up" (nodes -> coordinator, keyed by the sender), both reliable,
// KEEP_LAST 64, volatile. A node endpoint delivers only messages addressed to its node id or
// broadcast (-1); filtering happens on receipt, before any payload is parsed.
//
// Receipt: a data-available listener takes the samples on Cyclone's receive thread, offers each to
// the inline handler (set_inline_handler) and queues the rest for receive(), waking it through a
// condition variable only when something was queued. So a message for another node never wakes
// the caller, and a handled one costs no thread switch at all.
//
// Discovery: the participant reads CYCLONEDDS_URI as usual (configs/dds_loopback.xml for one host).
// receive() is not real-time safe on the first call (it sizes its buffers); later calls allocate
// only for the payload strings.

#include <memory>
#include <utility>
#include <vector>

#include "transport/transport.h"

namespace rths::transport {

struct DdsEndpointOptions {
  std::uint32_t domain_id = 0;
  bool coordinator = true;                 // false: a node
  std::int32_t node_id = kCoordinatorId;   // for a node, its id (messages to others are dropped)
  std::string topic_prefix = "rths";       // topics <prefix>_down and <prefix>_up
  int history_depth = 64;
  // QoS properties of the participant: the DDS Security ones (security::participant_properties)
  // or none. A participant with security talks only to participants of the same lab's PKI.
  std::vector<std::pair<std::string, std::string>> participant_properties;
};

class DdsEndpoint final : public Endpoint {
 public:
  explicit DdsEndpoint(const DdsEndpointOptions& options);
  ~DdsEndpoint() override;
  void send(const Message& message) override;
  std::optional<Message> receive(std::chrono::nanoseconds timeout) override;
  void interrupt() override;
  int matched_peers() const override;
  int matched_writers() const;
  // Waits until at least `writers` remote writers feed this endpoint and `readers` remote
  // readers listen to it. Throws std::runtime_error naming the counts on timeout.
  void wait_for_match(int readers, int writers, std::chrono::milliseconds timeout) const;
  void set_inline_handler(InlineHandler handler) override;
  void set_wake_threshold(int messages) override;

 private:
  struct Impl;
  DdsEndpointOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rths::transport
