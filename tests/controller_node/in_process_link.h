#pragma once
// An in-process datagram link for the controller exchange's tests: no socket, no port. Two ends
// share a pair of queues; what one end sends the other receives, in order, stamped on the
// clock the pair was made with (the clock the exchange under test runs on).
//   InProcessLinkPair pair(clock)   the two ends: node_end() (moved into the exchange, once) and
//                                   controller() (the test's end, playing the controller)
//   wait(deadline)                  true at once when a datagram is queued; else waits on a
//                                   condition variable for the span to the deadline on `clock`
//                                   (a manual clock that never moves: the span as it is now)
// Every datagram comes from the peer (from_peer true): what a foreign sender does to the real
// socket is UdpLink's to show (controller_exchange_test.cpp keeps those on UDP).

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <string>

#include "controller_node/udp_link.h"
#include "runtime/rt/clock.h"

namespace rths::test {

class InProcessLinkPair {
 public:
  explicit InProcessLinkPair(runtime::PacingClock& clock)
      : shared_(std::make_shared<Shared>(clock)),
        node_(std::make_unique<End>(shared_, 0, "controller (in process)")),
        controller_(shared_, 1, "node (in process)") {}

  // The node's end, for ControllerExchange's constructor (once).
  std::unique_ptr<controller_node::DatagramLink> node_end() { return std::move(node_); }
  controller_node::DatagramLink& controller() { return controller_; }

 private:
  struct Shared {
    explicit Shared(runtime::PacingClock& c) : clock(c) {}
    runtime::PacingClock& clock;
    std::mutex mutex;
    std::condition_variable arrived;
    std::deque<controller_node::Datagram> queue[2];  // [i]: what end i receives
  };

  class End final : public controller_node::DatagramLink {
   public:
    End(std::shared_ptr<Shared> shared, int side, std::string peer)
        : shared_(std::move(shared)), side_(side), peer_(std::move(peer)) {}
    int send(const std::uint8_t* bytes, std::size_t size) override {
      controller_node::Datagram d;
      d.size = size;
      std::memcpy(d.bytes.data(), bytes, std::min(size, d.bytes.size()));
      d.from_peer = true;
      {
        std::lock_guard lock(shared_->mutex);
        d.received_ns = shared_->clock.now_ns();
        shared_->queue[1 - side_].push_back(d);
      }
      shared_->arrived.notify_all();
      return 0;
    }
    bool wait(std::int64_t deadline_ns) const override {
      std::unique_lock lock(shared_->mutex);
      const std::int64_t span = deadline_ns - shared_->clock.now_ns();
      if (shared_->queue[side_].empty() && span > 0)
        shared_->arrived.wait_for(lock, std::chrono::nanoseconds(span),
                                  [this] { return !shared_->queue[side_].empty(); });
      return !shared_->queue[side_].empty();
    }
    bool try_receive(controller_node::Datagram& datagram) override {
      std::lock_guard lock(shared_->mutex);
      auto& queue = shared_->queue[side_];
      if (queue.empty()) return false;
      datagram = queue.front();
      queue.pop_front();
      return true;
    }
    std::string peer() const override { return peer_; }

   private:
    std::shared_ptr<Shared> shared_;
    int side_;
    std::string peer_;
  };

  std::shared_ptr<Shared> shared_;
  std::unique_ptr<End> node_;
  End controller_;
};

}  // namespace rths::test
