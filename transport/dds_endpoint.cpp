#include "transport/dds_endpoint.h"

#include <dds/dds.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "envelope.h"
#include "transport/dds.h"
#include "transport/message_mac.h"
#include "transport/writer_guids.h"

namespace rths::transport {

namespace {

// How long the first message to a node may wait for that node's command reader to match the
// writer it creates (volatile data written before the match would be lost), and then for the
// node to acknowledge it. Start-up only: the first addressed message is the ASSIGN answering the
// node's announcement, so the node is there.
constexpr auto kAddressedMatchTimeout = std::chrono::milliseconds(2000);

std::string node_topic_name(const std::string& prefix, std::int32_t node_id, const char* way) {
  return prefix + "_node" + std::to_string(node_id) + way;
}

}  // namespace

// One reader of one topic, owning the topic; `node` is the node whose topic it is.
struct DdsEndpoint::NodeReader {
  dds::EnvelopeTopic topic;
  dds::Reader reader;
  std::int32_t node;
};

// One writer of one topic, owning the topic; `guid` is the writer's, covered by the MAC of
// everything it writes.
struct DdsEndpoint::TopicWriter {
  dds::EnvelopeTopic topic;
  dds::Writer writer;
  dds::Guid guid;
};

struct DdsEndpoint::Impl {
  Impl(const DdsEndpointOptions& o, const dds::QosSpec& qos)
      : options(o),
        qos(qos),
        mac(o.run_secret.empty() ? nullptr : std::make_unique<MessageMac>(o.run_secret)),
        participant(o.domain_id, o.participant_properties) {
    if (o.coordinator) return;
    dds::EnvelopeTopic up(participant, node_topic_name(o.topic_prefix, o.node_id, "_up"), qos);
    dds::Writer w(participant, up, qos);
    const dds::Guid guid = w.guid();
    own.reset(new TopicWriter{std::move(up), std::move(w), guid});
    add_reader(node_topic_name(o.topic_prefix, o.node_id, "_down"), o.node_id);
  }
  // No reader is added once destruction starts; the lock is not held while a running listener
  // (which takes it) is waited for.
  ~Impl() {
    for (auto& r : readers) r->reader.clear_listener();
  }

  static void on_data(dds::Handle reader, void* self) { static_cast<Impl*>(self)->drain(reader); }
  // Runs on Cyclone's receive thread.
  void drain(dds::Handle from);
  // Receive thread: hands `m` to the inline handler, or queues it (moved) for receive() when
  // there is none or it did not take it. True when queued.
  bool deliver(Message& m);
  // The coordinator's writer of node_id's command topic, created (and matched) on first use
  // (`created` then true).
  const TopicWriter& addressed_writer(std::int32_t node_id, bool& created);
  // Whether every reader matched to `w` has acknowledged all `w` wrote, waiting up to `timeout`.
  static bool acknowledged(const TopicWriter& w, std::chrono::nanoseconds timeout);
  // Writes `sample` (the fields of `m`) with `w`, its MAC first made for w's GUID when there is
  // a run secret.
  void write(const TopicWriter& w, const Message& m, rths_dds_Envelope& sample) const;
  // A reader of `topic`, whose messages are stamped as carried by `node`'s topic.
  void add_reader(const std::string& topic, std::int32_t node);
  // The node whose topic `reader` reads; nullopt for a reader this endpoint does not own.
  std::optional<std::int32_t> topic_node_of(dds::Handle reader);
  // Without a run secret, true; with one, whether the sample's MAC verifies over its own fields
  // and the GUID of the writer it came from (`writer`, a publication handle matched to
  // `reader`), before anything is copied out of it; else counted and its newest kept, unformatted.
  bool authentic(const rths_dds_Envelope& s, std::int32_t topic_node, dds::Handle reader,
                 std::uint64_t writer);
  // The GUID of `writer` (matched to `reader`): from `guids` once its first message verified,
  // else asked of DDS (an allocation). nullopt when DDS no longer knows the writer.
  std::optional<WriterGuid> guid_of(dds::Handle reader, std::uint64_t writer) const;

  const DdsEndpointOptions options;
  const dds::QosSpec qos;
  const std::unique_ptr<MessageMac> mac;  // null without a run secret
  // The newest dropped sample's fields: a flood costs a count and four stores each, and the text
  // is made only when asked for (unauthenticated()).
  struct Dropped {
    std::uint64_t count = 0;
    std::int32_t kind = 0, node_id = 0, topic_node = 0;
    std::uint64_t writer = 0;
  };
  mutable std::mutex unauthenticated_mutex;
  Dropped dropped;
  // Writers (publication handles) that sent a message whose MAC failed: the run's own processes
  // never do, so their later samples are dropped by a lookup, before any hash. At most
  // kMaxForgers remembered (a forger that keeps making writers pays one MAC per new writer).
  static constexpr std::size_t kMaxForgers = 256;
  std::vector<std::uint64_t> forgers;  // under unauthenticated_mutex
  std::atomic<bool> any_forger{false};
  bool known_forger(std::uint64_t writer);
  // The GUIDs of the writers whose messages verified, by publication handle.
  WriterGuids guids;
  // Shared between the receive thread and the caller; declared before the DDS entities so they
  // outlive the listener.
  std::mutex mutex;
  std::condition_variable arrived, handler_idle;
  std::deque<Message> pending;
  bool interrupted = false;
  std::shared_ptr<const InlineHandler> handler;
  int handler_calls = 0;  // invocations in progress
  std::atomic<std::uint64_t> samples_taken{0};

  dds::Participant participant;
  std::unique_ptr<TopicWriter> own;  // node only: <prefix>_node<id>_up
  // Node: <prefix>_node<id>_down; coordinator: <prefix>_node<id>_up of every node it listens
  // to. Only added to (entries never move: the listener reads them).
  std::mutex readers_mutex;
  std::vector<std::unique_ptr<NodeReader>> readers;
  // Coordinator only: one topic and writer per addressee, so a command reaches its node only.
  std::mutex writers_mutex;
  std::map<std::int32_t, std::unique_ptr<TopicWriter>> addressed_writers;
};

void DdsEndpoint::Impl::add_reader(const std::string& name, std::int32_t node) {
  dds::EnvelopeTopic topic(participant, name, qos);
  dds::Reader reader(participant, topic, qos, &Impl::on_data, this);
  std::lock_guard lock(readers_mutex);
  readers.push_back(
      std::make_unique<NodeReader>(NodeReader{std::move(topic), std::move(reader), node}));
}

std::optional<std::int32_t> DdsEndpoint::Impl::topic_node_of(dds::Handle reader) {
  std::lock_guard lock(readers_mutex);
  for (const auto& r : readers)
    if (r->reader.get() == reader) return r->node;
  return std::nullopt;
}

const DdsEndpoint::TopicWriter& DdsEndpoint::Impl::addressed_writer(std::int32_t node_id,
                                                                    bool& created) {
  std::lock_guard lock(writers_mutex);
  auto& slot = addressed_writers[node_id];
  created = !slot;
  if (created) {
    dds::EnvelopeTopic topic(participant, node_topic_name(options.topic_prefix, node_id, "_down"),
                             qos);
    dds::Writer w(participant, topic, qos);
    const dds::Guid guid = w.guid();
    slot.reset(new TopicWriter{std::move(topic), std::move(w), guid});
    const auto deadline = std::chrono::steady_clock::now() + kAddressedMatchTimeout;
    while (slot->writer.matched_readers() < 1 && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return *slot;  // entries never move or go while the endpoint lives
}

bool DdsEndpoint::Impl::acknowledged(const TopicWriter& w, std::chrono::nanoseconds timeout) {
  return dds_wait_for_acks(w.writer.get(), static_cast<dds_duration_t>(timeout.count())) ==
         DDS_RETCODE_OK;
}

bool DdsEndpoint::acknowledged(std::int32_t node_id, std::chrono::nanoseconds timeout) const {
  const TopicWriter* w = nullptr;
  {
    std::lock_guard lock(impl_->writers_mutex);
    const auto it = impl_->addressed_writers.find(node_id);
    if (it == impl_->addressed_writers.end()) return false;
    w = it->second.get();
  }
  return Impl::acknowledged(*w, timeout);
}

void DdsEndpoint::listen_to(std::int32_t node_id) {
  if (!options_.coordinator) return;
  {
    std::lock_guard lock(impl_->readers_mutex);
    for (const auto& r : impl_->readers)
      if (r->node == node_id) return;
  }
  impl_->add_reader(node_topic_name(options_.topic_prefix, node_id, "_up"), node_id);
}

const std::vector<std::string>& dds_receive_thread_names() {
  static const std::vector<std::string> names{"recv", "recvUC", "recvMC", "dq.user"};
  return names;
}

std::int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

namespace {

// `options` with its topic prefix resolved: an empty one is the process's scoped prefix.
DdsEndpointOptions with_topic_prefix(DdsEndpointOptions options) {
  if (options.topic_prefix.empty()) options.topic_prefix = scoped_topic_prefix();
  return options;
}

}  // namespace

DdsEndpoint::DdsEndpoint(const DdsEndpointOptions& options)
    : options_(with_topic_prefix(options)),
      impl_(std::make_unique<Impl>(options_, dds::QosSpec{options_.history_depth, {}})) {}

DdsEndpoint::~DdsEndpoint() = default;

void DdsEndpoint::send(const Message& m) {
  rths_dds_Envelope sample{};
  // The sample only borrows our buffers: dds_write serialises before returning.
  sample.run_id = const_cast<char*>(m.run_id.c_str());
  sample.node_id = m.node_id;
  sample.kind = m.kind;
  sample.step = m.step;
  sample.sent_ns = m.sent_ns != 0 ? m.sent_ns : realtime_ns();
  sample.echo_ns = m.echo_ns;
  sample.payload._length = static_cast<uint32_t>(m.payload.size());
  sample.payload._maximum = sample.payload._length;
  sample.payload._buffer = reinterpret_cast<uint8_t*>(const_cast<char*>(m.payload.data()));
  sample.payload._release = false;
  if (!options_.coordinator) return impl_->write(*impl_->own, m, sample);
  if (m.node_id != kBroadcastId) {
    bool created = false;
    const TopicWriter& w = impl_->addressed_writer(m.node_id, created);
    impl_->write(w, m, sample);
    // A new writer is matched on our side before the node's reader has discovered it (discovery
    // runs each way on its own). Cyclone's reader drops what reaches it before then, and repairs
    // the first such sample at once but a later one only after its NackDelay (100 ms), holding
    // every command behind it: the node's first answers then come 100 ms late, past a 40 ms
    // answer window. So nothing more is written to the node until it has acknowledged the first.
    if (created && !Impl::acknowledged(w, kAddressedMatchTimeout))
      spdlog::warn(
          "DDS: node {} did not acknowledge the first message on its command topic within {} "
          "ms; what follows may reach it only after the reader's repair delay (about 100 ms)",
          m.node_id, kAddressedMatchTimeout.count());
    return;
  }
  // To each node addressed so far, without allocating (a heartbeat goes out from the loop); each
  // writer has its own GUID, so each copy its own MAC.
  std::lock_guard lock(impl_->writers_mutex);
  for (const auto& [node, w] : impl_->addressed_writers) impl_->write(*w, m, sample);
}

void DdsEndpoint::Impl::write(const TopicWriter& w, const Message& m,
                              rths_dds_Envelope& sample) const {
  if (mac) {
    const Mac signed_mac = mac->sign(
        m, sample.sent_ns, options.coordinator ? Direction::kDown : Direction::kUp, w.guid);
    std::copy(signed_mac.begin(), signed_mac.end(), sample.mac);
  }
  dds::check(dds_write(w.writer.get(), &sample), "dds_write");
}

void DdsEndpoint::Impl::drain(dds::Handle from) {
  constexpr int kBatch = 16;
  void* samples[kBatch] = {};
  dds_sample_info_t infos[kBatch];
  bool queued = false;
  const std::optional<std::int32_t> topic_node = topic_node_of(from);
  if (!topic_node) return;
  for (;;) {
    // A failing take here has no caller to throw to; the data stays and the next arrival retries.
    const dds_return_t n = dds_take(from, samples, infos, kBatch, kBatch);
    if (n <= 0) break;  // (after a full batch: what was queued still needs its wake-up)
    const std::int64_t now = realtime_ns();
    for (int i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      samples_taken.fetch_add(1, std::memory_order_relaxed);
      const auto* s = static_cast<const rths_dds_Envelope*>(samples[i]);
      if (!options.coordinator && s->node_id != options.node_id && s->node_id != kBroadcastId)
        continue;
      if (known_forger(infos[i].publication_handle) ||
          !authentic(*s, *topic_node, from, infos[i].publication_handle))
        continue;
      // Per receive thread, reused: assigning into its strings allocates nothing once they have
      // grown to the largest message (moved into the queue, it starts over).
      thread_local Message m;
      m.run_id = s->run_id ? s->run_id : "";
      m.node_id = s->node_id;
      m.kind = s->kind;
      m.step = s->step;
      m.sent_ns = s->sent_ns;
      m.echo_ns = s->echo_ns;
      m.payload.assign(reinterpret_cast<const char*>(s->payload._buffer), s->payload._length);
      m.received_ns = now;
      m.topic_node = *topic_node;
      m.writer = infos[i].publication_handle;
      queued |= deliver(m);
    }
    dds_return_loan(from, samples, n);
    if (n < kBatch) break;
  }
  if (!queued) return;
  std::lock_guard lock(mutex);
  arrived.notify_one();
}

bool DdsEndpoint::Impl::deliver(Message& m) {
  std::shared_ptr<const InlineHandler> h;
  {
    std::lock_guard lock(mutex);
    h = handler;
    if (h) ++handler_calls;
  }
  bool consumed = false;
  if (h) {
    try {
      consumed = (*h)(m);
    } catch (...) {
      consumed = false;  // the caller's receive() sees it and handles (or throws) there
    }
    std::lock_guard lock(mutex);
    if (--handler_calls == 0) handler_idle.notify_all();
  }
  if (consumed) return false;
  std::lock_guard lock(mutex);
  pending.push_back(std::move(m));
  return true;
}

std::optional<WriterGuid> DdsEndpoint::Impl::guid_of(dds::Handle reader,
                                                     std::uint64_t writer) const {
  if (const WriterGuid* known = guids.find(writer)) return *known;
  return dds::publication_guid(reader, writer);
}

bool DdsEndpoint::Impl::authentic(const rths_dds_Envelope& s, std::int32_t topic_node,
                                  dds::Handle reader, std::uint64_t writer) {
  if (!mac) return true;
  const std::optional<WriterGuid> guid = guid_of(reader, writer);
  MacInput fields;
  if (guid) fields.writer = *guid;
  fields.run_id = s.run_id ? std::string_view(s.run_id) : std::string_view();
  fields.node_id = s.node_id;
  fields.kind = s.kind;
  fields.step = s.step;
  fields.sent_ns = s.sent_ns;
  fields.echo_ns = s.echo_ns;
  fields.payload =
      std::string_view(reinterpret_cast<const char*>(s.payload._buffer), s.payload._length);
  Mac received;
  std::copy(s.mac, s.mac + kMacBytes, received.begin());
  // A writer DDS no longer knows (gone since its sample) is not verified against a guessed GUID:
  // dropped and counted, never remembered as a forger.
  if (guid &&
      mac->verify(fields, options.coordinator ? Direction::kUp : Direction::kDown, received)) {
    guids.add(writer, *guid);
    return true;
  }
  std::lock_guard lock(unauthenticated_mutex);
  if (guid && forgers.size() < kMaxForgers &&
      std::find(forgers.begin(), forgers.end(), writer) == forgers.end()) {
    forgers.push_back(writer);
    any_forger.store(true, std::memory_order_release);
  }
  ++dropped.count;
  dropped.kind = s.kind;
  dropped.node_id = s.node_id;
  dropped.topic_node = topic_node;
  dropped.writer = writer;
  return false;
}

bool DdsEndpoint::Impl::known_forger(std::uint64_t writer) {
  if (!mac || !any_forger.load(std::memory_order_acquire)) return false;
  std::lock_guard lock(unauthenticated_mutex);
  if (std::find(forgers.begin(), forgers.end(), writer) == forgers.end()) return false;
  ++dropped.count;  // the newest drop stays the one whose MAC was checked
  return true;
}

Unauthenticated DdsEndpoint::unauthenticated() const {
  Impl::Dropped d;
  {
    std::lock_guard lock(impl_->unauthenticated_mutex);
    d = impl_->dropped;
  }
  Unauthenticated u;
  u.count = d.count;
  if (d.count == 0) return u;
  u.last = "kind " + std::to_string(d.kind) + " as node " + std::to_string(d.node_id) +
           " on node " + std::to_string(d.topic_node) + "'s topic, writer " +
           std::to_string(d.writer);
  return u;
}

std::uint64_t DdsEndpoint::unauthenticated_count() const {
  std::lock_guard lock(impl_->unauthenticated_mutex);
  return impl_->dropped.count;
}

std::optional<Message> DdsEndpoint::receive(std::chrono::nanoseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::unique_lock lock(impl_->mutex);
  impl_->arrived.wait_until(lock, deadline,
                            [&] { return !impl_->pending.empty() || impl_->interrupted; });
  if (!impl_->pending.empty()) {
    Message m = std::move(impl_->pending.front());
    impl_->pending.pop_front();
    return m;
  }
  if (impl_->interrupted) impl_->interrupted = false;
  return std::nullopt;
}

void DdsEndpoint::interrupt() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->interrupted = true;
  }
  impl_->arrived.notify_all();
}

void DdsEndpoint::set_inline_handler(InlineHandler handler) {
  std::unique_lock lock(impl_->mutex);
  impl_->handler = handler ? std::make_shared<const InlineHandler>(std::move(handler)) : nullptr;
  impl_->handler_idle.wait(lock, [&] { return impl_->handler_calls == 0; });
}

std::uint64_t DdsEndpoint::samples_taken() const {
  return impl_->samples_taken.load(std::memory_order_relaxed);
}

int DdsEndpoint::matched_peers() const {
  if (impl_->own) return impl_->own->writer.matched_readers();
  std::lock_guard lock(impl_->writers_mutex);
  int readers = 0;
  for (const auto& [id, w] : impl_->addressed_writers) readers += w->writer.matched_readers();
  return readers;
}
int DdsEndpoint::matched_writers() const {
  std::lock_guard lock(impl_->readers_mutex);
  int writers = 0;
  for (const auto& r : impl_->readers) writers += r->reader.matched_writers();
  return writers;
}

void DdsEndpoint::wait_for_match(int readers, int writers,
                                 std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const int r = matched_peers();
    const int w = matched_writers();
    if (r >= readers && w >= writers) return;
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("DDS domain " + std::to_string(options_.domain_id) + ": matched " +
                               std::to_string(r) + "/" + std::to_string(readers) + " readers and " +
                               std::to_string(w) + "/" + std::to_string(writers) +
                               " writers after " + std::to_string(timeout.count()) + " ms");
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

}  // namespace rths::transport
