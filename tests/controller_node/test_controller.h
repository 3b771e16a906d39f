#pragma once
// Shared by the exchange and hold tests: the controller's end of a link, one actuator: a UDP
// socket on 127.0.0.1 bound to the link's peer port and connected to the node, or the test's end
// of an in-process link (in_process_link.h) with the clock the exchange runs on.
//   feedback(counter, drift m, force N, status) -> a feedback frame's bytes
//   send(bytes), answer(counter, drift, force, status): one datagram to the node
//   take(seconds) -> the next command frame, or one with counter 0 when none came in time
// await_answer(node, seconds): what the node makes of its link within `seconds` (real time; the
// node is asked at its own clock's now), the first answer or fault, else kNone.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "controller_node/controller_exchange.h"
#include "controller_node/frame.h"
#include "controller_node/udp_link.h"

namespace rths::test {

inline runtime::PacingClock& real_clock() {
  static runtime::MonotonicClock clock;
  return clock;
}

struct TestController {
  config::ControllerLink link;
  std::unique_ptr<controller_node::UdpLink> socket;  // the UDP end, when the test runs on UDP
  controller_node::DatagramLink& end;
  runtime::PacingClock& clock;
  explicit TestController(const config::ControllerLink& l)
      : link(l),
        socket(std::make_unique<controller_node::UdpLink>(l.peer_address(), l.peer_port(),
                                                          l.local_address(), l.local_port())),
        end(*socket),
        clock(real_clock()) {}
  TestController(const config::ControllerLink& l, controller_node::DatagramLink& in_process,
                 runtime::PacingClock& c)
      : link(l), end(in_process), clock(c) {}

  std::vector<std::uint8_t> feedback(std::int64_t counter, double drift, double force,
                                     std::int64_t status = 0) {
    controller_node::FrameValues v;
    v.counter = counter;
    v.status = status;
    v.measured_displacement = {drift};
    v.measured_force = {force};
    std::vector<std::uint8_t> bytes;
    EXPECT_TRUE(controller_node::encode(link.feedback(), v, bytes));
    return bytes;
  }
  void send(const std::vector<std::uint8_t>& frame) { end.send(frame.data(), frame.size()); }
  void answer(std::int64_t counter, double drift, double force, std::int64_t status = 0) {
    send(feedback(counter, drift, force, status));
  }
  controller_node::FrameValues take(double seconds = 2.0) {
    controller_node::FrameValues v;
    controller_node::Datagram d;
    const std::int64_t until = clock.now_ns() + static_cast<std::int64_t>(seconds * 1e9);
    while (!end.try_receive(d))
      if (!end.wait(until)) return v;
    EXPECT_EQ(controller_node::decode(link.command(), d.bytes.data(), d.size, 1, v),
              controller_node::FrameVerdict::kOk);
    return v;
  }
};

inline controller_node::ControllerExchange::Answer await_answer(
    controller_node::ControllerExchange& node, double seconds = 2.0) {
  const std::int64_t until =
      controller_node::monotonic_ns() + static_cast<std::int64_t>(seconds * 1e9);
  for (;;) {
    auto a = node.next(node.now_ns());
    if (a.outcome != controller_node::ControllerExchange::Outcome::kNone ||
        controller_node::monotonic_ns() > until)
      return a;
    node.wait(node.now_ns() + 1'000'000);
  }
}

}  // namespace rths::test
