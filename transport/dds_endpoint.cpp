#include "transport/dds_endpoint.h"

#include <dds/dds.h>

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "envelope.h"
#include "transport/dds.h"

namespace rths::transport {

struct DdsEndpoint::Impl {
  Impl(const DdsEndpointOptions& o, const dds::QosSpec& qos)
      : options(o),
        participant(o.domain_id, o.participant_properties),
        down(participant, o.topic_prefix + "_down", qos),
        up(participant, o.topic_prefix + "_up", qos),
        writer(participant, o.coordinator ? down : up, qos),
        reader(participant, o.coordinator ? up : down, qos, &Impl::on_data, this) {}
  ~Impl() { reader.clear_listener(); }

  static void on_data(dds::Handle, void* self) { static_cast<Impl*>(self)->drain(); }
  // Runs on Cyclone's receive thread.
  void drain();

  const DdsEndpointOptions options;
  // Shared between the receive thread and the caller; declared before the DDS entities so they
  // outlive the listener.
  std::mutex mutex;
  std::condition_variable arrived, handler_idle;
  std::deque<Message> pending;
  bool interrupted = false;
  std::size_t wake_threshold = 1;
  std::shared_ptr<const InlineHandler> handler;
  int handler_calls = 0;  // invocations in progress

  dds::Participant participant;
  dds::EnvelopeTopic down, up;
  dds::Writer writer;
  dds::Reader reader;
};

std::int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

DdsEndpoint::DdsEndpoint(const DdsEndpointOptions& options)
    : options_(options),
      impl_(std::make_unique<Impl>(options, dds::QosSpec{options.history_depth, {}})) {}

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
  sample.payload._buffer =
      reinterpret_cast<uint8_t*>(const_cast<char*>(m.payload.data()));
  sample.payload._release = false;
  dds::check(dds_write(impl_->writer.get(), &sample), "dds_write");
}

void DdsEndpoint::Impl::drain() {
  constexpr int kBatch = 16;
  void* samples[kBatch] = {};
  dds_sample_info_t infos[kBatch];
  bool queued = false;
  for (;;) {
    // A failing take here has no caller to throw to; the data stays and the next arrival retries.
    const dds_return_t n = dds_take(reader.get(), samples, infos, kBatch, kBatch);
    if (n <= 0) return;
    const std::int64_t now = realtime_ns();
    for (int i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      const auto* s = static_cast<const rths_dds_Envelope*>(samples[i]);
      if (!options.coordinator && s->node_id != options.node_id && s->node_id != kBroadcastId)
        continue;
      Message m;
      m.run_id = s->run_id ? s->run_id : "";
      m.node_id = s->node_id;
      m.kind = s->kind;
      m.step = s->step;
      m.sent_ns = s->sent_ns;
      m.echo_ns = s->echo_ns;
      m.payload.assign(reinterpret_cast<const char*>(s->payload._buffer), s->payload._length);
      m.received_ns = now;
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
      if (!consumed) {
        std::lock_guard lock(mutex);
        pending.push_back(std::move(m));
        queued = true;
      }
    }
    dds_return_loan(reader.get(), samples, n);
    if (n < kBatch) break;
  }
  if (!queued) return;
  std::lock_guard lock(mutex);
  if (pending.size() >= wake_threshold) arrived.notify_one();
}

std::optional<Message> DdsEndpoint::receive(std::chrono::nanoseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::unique_lock lock(impl_->mutex);
  impl_->arrived.wait_until(lock, deadline, [&] {
    return impl_->pending.size() >= impl_->wake_threshold || impl_->interrupted;
  });
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

void DdsEndpoint::set_wake_threshold(int messages) {
  std::lock_guard lock(impl_->mutex);
  impl_->wake_threshold = static_cast<std::size_t>(std::max(1, messages));
}

int DdsEndpoint::matched_peers() const { return impl_->writer.matched_readers(); }
int DdsEndpoint::matched_writers() const { return impl_->reader.matched_writers(); }

void DdsEndpoint::wait_for_match(int readers, int writers,
                                 std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const int r = matched_peers();
    const int w = matched_writers();
    if (r >= readers && w >= writers) return;
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("DDS domain " + std::to_string(options_.domain_id) +
                               ": matched " + std::to_string(r) + "/" + std::to_string(readers) +
                               " readers and " + std::to_string(w) + "/" +
                               std::to_string(writers) + " writers after " +
                               std::to_string(timeout.count()) + " ms");
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

}  // namespace rths::transport
