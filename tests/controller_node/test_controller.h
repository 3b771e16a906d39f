#pragma once
// Shared by the exchange and hold tests: the controller's end of a link on 127.0.0.1 (a UDP
// socket bound to the link's peer port and connected to the node), one actuator.
//   feedback(counter, drift m, force N, status) -> a feedback frame's bytes
//   send(bytes), answer(counter, drift, force, status): one datagram to the node
//   take(seconds) -> the next command frame, or one with counter 0 when none came in time
// await_answer(node, seconds): what the node makes of its link within `seconds`, the first answer
// or fault, else kNone.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "controller_node/controller_exchange.h"
#include "controller_node/frame.h"
#include "controller_node/udp_link.h"

namespace rths::test {

struct TestController {
  config::ControllerLink link;
  controller_node::UdpLink udp;
  explicit TestController(const config::ControllerLink& l)
      : link(l), udp(l.peer_address(), l.peer_port(), l.local_address(), l.local_port()) {}

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
  void send(const std::vector<std::uint8_t>& frame) { udp.send(frame.data(), frame.size()); }
  void answer(std::int64_t counter, double drift, double force, std::int64_t status = 0) {
    send(feedback(counter, drift, force, status));
  }
  controller_node::FrameValues take(double seconds = 2.0) {
    controller_node::FrameValues v;
    controller_node::Datagram d;
    const std::int64_t until =
        controller_node::monotonic_ns() + static_cast<std::int64_t>(seconds * 1e9);
    while (!udp.try_receive(d))
      if (!udp.wait(until)) return v;
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
    auto a = node.next(controller_node::monotonic_ns());
    if (a.outcome != controller_node::ControllerExchange::Outcome::kNone ||
        controller_node::monotonic_ns() > until)
      return a;
    node.wait(std::min(until, controller_node::monotonic_ns() + 1'000'000));
  }
}

}  // namespace rths::test
