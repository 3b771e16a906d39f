#pragma once
// Endpoint over Cyclone DDS. Two topics per node, all reliable, KEEP_LAST 64, volatile:
//   "rths_node<id>_down"  coordinator -> node <id>: everything addressed to that node
//   "rths_node<id>_up"    node <id> -> coordinator: everything node <id> sends
// ("rths" is the default prefix: RTHS_DDS_SCOPE scopes it per run, transport/topic_scope.h)
// A coordinator's broadcast (node id -1) is written to the command topic of every node it has
// addressed so far: no topic is shared, so a node's DDS Security permissions can allow it its
// own two topics and nothing else (`rths pki init`). The coordinator reads the up topic of each
// node it listens to (listen_to). Every message taken is stamped with the node whose topic
// carried it (topic_node) and the DDS instance handle of the writer that sent it (writer), so a
// receiver can check the envelope's node id against the topic and pin each peer's writer: a
// participant that claims another node's id is told apart.
// One topic per addressee, not one shared topic, also because DDS delivers every sample to every
// matched reader: on a shared topic each command woke every node process, to be thrown away by
// all but one. The coordinator creates a node's writer on the first message addressed to it and
// waits (up to 2 s, at start-up) for the node's reader to match, so that first message is not
// lost, and then (up to 2 s more) for the node to acknowledge it, so that nothing else is written
// to the node before its reader is in step with the new writer (dds_endpoint.cpp, send()). Order
// holds per topic only. A node endpoint also drops anything not addressed to it or
// broadcast, before any payload is parsed.
//
// Receipt: a data-available listener takes the samples on Cyclone's receive thread, offers each to
// the inline handler (set_inline_handler) and queues the rest for receive(), waking it through a
// condition variable only when something was queued. So a message for another node never wakes
// the caller, and a handled one costs no thread switch at all.
//
// Discovery: the participant reads CYCLONEDDS_URI as usual (configs/dds_loopback.xml for one host).
// A message the inline handler consumes costs no allocation once warm: the receive thread decodes
// each sample into a message of its own whose strings keep their capacity. A message queued for
// receive() is moved out of it (the queue and the next decode allocate).

#include <memory>
#include <utility>
#include <vector>

#include "transport/topic_scope.h"
#include "transport/transport.h"
#include "transport/unauthenticated.h"

namespace rths::transport {

// The names of Cyclone DDS's threads that carry a run's messages into a process (its receive
// threads and the user-data delivery queue): the listener above, and so the inline handler, runs
// on them. A process that raises its loop to real-time priority raises these with it
// (runtime/rt/fifo.h), or a message would wait behind every ordinary thread of the host.
// Cyclone 0.10's config names only "recv" among them (recvUC and recvMC are refused), so the
// threads are raised by name once the participant exists instead of through CYCLONEDDS_URI.
const std::vector<std::string>& dds_receive_thread_names();

struct DdsEndpointOptions {
  std::uint32_t domain_id = 0;
  bool coordinator = true;                // false: a node
  std::int32_t node_id = kCoordinatorId;  // for a node, its id (messages to others are dropped)
  // Topics <prefix>_node<id>_down and _up. Empty: scoped_topic_prefix() when the endpoint opens
  // ("rths", or "rths_<scope>" under RTHS_DDS_SCOPE: transport/topic_scope.h), so every endpoint
  // of a run's processes agrees; a bad scope makes the constructor throw std::invalid_argument
  // naming it.
  std::string topic_prefix;
  int history_depth = 64;
  // QoS properties of the participant: the DDS Security ones (security::participant_properties)
  // or none. A participant with security talks only to participants of the same lab's PKI.
  std::vector<std::pair<std::string, std::string>> participant_properties;
  // The run secret (security/run_secret.h), or empty. Non-empty: every message sent carries a
  // MAC under it (transport/message_mac.h) that covers the GUID of the writer sending it (a
  // broadcast: one MAC per node's writer), and every message received without a valid one for
  // the writer it came from (the GUID DDS reports for its publication handle, looked up once
  // per writer and then kept) is dropped on the receive thread before any handler or receive()
  // sees it, counted and named (unauthenticated()): a stranger's forgery, and a genuine message
  // replayed byte for byte from another writer. The writer that sent it is remembered, and its
  // later messages are dropped (and counted) without computing their MAC.
  std::string run_secret;
};

class DdsEndpoint final : public Endpoint {
 public:
  explicit DdsEndpoint(const DdsEndpointOptions& options);
  ~DdsEndpoint() override;
  void send(const Message& message) override;
  std::optional<Message> receive(std::chrono::nanoseconds timeout) override;
  void interrupt() override;
  int matched_peers() const override;
  void listen_to(std::int32_t node_id) override;
  // Messages dropped unread for want of a valid MAC (none without a run secret). Thread safe;
  // takes a mutex and copies a string.
  Unauthenticated unauthenticated() const;
  // The count alone: a mutex, no allocation (a node's heartbeats carry it).
  std::uint64_t unauthenticated_count() const;
  // Coordinator: whether node `node_id`'s readers have acknowledged every message addressed to
  // it so far, waiting up to `timeout` (0: asks without waiting); false before the first.
  bool acknowledged(std::int32_t node_id, std::chrono::nanoseconds timeout) const;
  // Remote writers feeding any of this endpoint's readers.
  int matched_writers() const;
  // Waits until at least `writers` remote writers feed this endpoint and `readers` remote
  // readers listen to it (a coordinator's writers exist once it has addressed a node). Throws
  // std::runtime_error naming the counts on timeout.
  void wait_for_match(int readers, int writers, std::chrono::milliseconds timeout) const;
  void set_inline_handler(InlineHandler handler) override;
  // Samples taken off DDS so far, including any dropped as not addressed to this node (with one
  // topic per addressee, a node takes only its own and broadcasts).
  std::uint64_t samples_taken() const;

 private:
  struct Impl;
  struct NodeReader;
  struct TopicWriter;
  DdsEndpointOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rths::transport
