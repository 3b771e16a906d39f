#include "transport/dds_endpoint.h"

#include <dds/dds.h>

#include <stdexcept>
#include <thread>

#include "envelope.h"
#include "transport/dds.h"

namespace rths::transport {

struct DdsEndpoint::Impl {
  Impl(const DdsEndpointOptions& o, const dds::QosSpec& qos)
      : participant(o.domain_id),
        down(participant, o.topic_prefix + "_down", qos),
        up(participant, o.topic_prefix + "_up", qos),
        writer(participant, o.coordinator ? down : up, qos),
        reader(participant, o.coordinator ? up : down, qos),
        guard(participant),
        waitset(participant, reader, guard) {}
  dds::Participant participant;
  dds::EnvelopeTopic down, up;
  dds::Writer writer;
  dds::Reader reader;
  dds::GuardCondition guard;
  dds::WaitSet waitset;
};

std::int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

DdsEndpoint::DdsEndpoint(const DdsEndpointOptions& options)
    : impl_(std::make_unique<Impl>(options, dds::QosSpec{options.history_depth, {}})),
      options_(options) {}

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

void DdsEndpoint::drain() {
  constexpr int kBatch = 16;
  void* samples[kBatch] = {};
  dds_sample_info_t infos[kBatch];
  for (;;) {
    const dds_return_t n = dds::check(
        dds_take(impl_->reader.get(), samples, infos, kBatch, kBatch), "dds_take");
    if (n == 0) return;
    const std::int64_t now = realtime_ns();
    for (int i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      const auto* s = static_cast<const rths_dds_Envelope*>(samples[i]);
      if (!options_.coordinator && s->node_id != options_.node_id && s->node_id != kBroadcastId)
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
      pending_.push_back(std::move(m));
    }
    dds::check(dds_return_loan(impl_->reader.get(), samples, n), "dds_return_loan");
    if (n < kBatch) return;
  }
}

std::optional<Message> DdsEndpoint::receive(std::chrono::nanoseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (pending_.empty()) drain();
    if (!pending_.empty()) {
      Message m = std::move(pending_.front());
      pending_.pop_front();
      return m;
    }
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= std::chrono::nanoseconds::zero()) return std::nullopt;
    if (!impl_->waitset.wait(left)) {
      drain();
      if (pending_.empty()) return std::nullopt;
      continue;
    }
    drain();
    if (pending_.empty()) {
      // Woken by the guard (interrupt) or by data for another node.
      bool triggered = false;
      dds::check(dds_read_guardcondition(impl_->guard.get(), &triggered),
                 "dds_read_guardcondition");
      if (triggered) {
        impl_->guard.reset();
        return std::nullopt;
      }
    }
  }
}

void DdsEndpoint::interrupt() { impl_->guard.trigger(); }

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
