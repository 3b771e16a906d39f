// The judged exchange with a controller over real UDP sockets on 127.0.0.1: a controller thread
// answers each command frame as told, and a rogue socket (another port) sends frames of its own.
// Every rejected frame is counted by cause and named; none is applied. UDP ports 47100-47139.
#include "controller_node/controller_exchange.h"

#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <future>
#include <limits>

#include "link_text.h"

namespace rths::controller_node {
namespace {

using Outcome = ControllerExchange::Outcome;
using Frames = std::vector<std::vector<std::uint8_t>>;

// The controller's end of the link: reads one command frame, returns what it decoded, and sends
// each of `answers(command)` (frames in order).
struct Controller {
  config::ControllerLink link;
  UdpLink udp;
  explicit Controller(const config::ControllerLink& l)
      : link(l), udp(l.peer_address(), l.peer_port(), l.local_address(), l.local_port()) {}

  std::vector<std::uint8_t> feedback(std::int64_t counter, double drift, double force,
                                     std::int64_t status = 0) {
    FrameValues v;
    v.counter = counter;
    v.status = status;
    v.measured_displacement = {drift};
    v.measured_force = {force};
    std::vector<std::uint8_t> bytes;
    EXPECT_TRUE(encode(link.feedback(), v, bytes));
    return bytes;
  }
  FrameValues take() {
    const auto d = udp.receive(monotonic_ns() + 2'000'000'000);
    FrameValues v;
    if (!d) return v;
    EXPECT_EQ(decode(link.command(), d->bytes.data(), d->size, 1, v), FrameVerdict::kOk);
    return v;
  }
  std::future<FrameValues> answer(std::function<Frames(const FrameValues&)> answers) {
    return std::async(std::launch::async, [this, answers] {
      const FrameValues command = take();
      for (const auto& frame : answers(command)) udp.send(frame);
      return command;
    });
  }
};

ExchangeSettings settings(double timeout = 0.5, bool real_time = false, int window = 1) {
  ExchangeSettings s;
  s.actuators = 1;
  s.reply_timeout = timeout;
  s.real_time = real_time;
  s.lost_window = window;
  s.max_drift = 0.1;
  s.max_force = 1e5;
  return s;
}

TEST(ControllerExchange, AnAnswerEchoingTheCounterIsAppliedWithItsRoundTrip) {
  const auto link = test::controller_link(47100, 47101);
  ControllerExchange node(link, settings());
  Controller controller(link);
  auto seen = controller.answer([&](const FrameValues& c) {
    return Frames{controller.feedback(c.counter, c.target_displacement[0] * 0.5, 1234.5)};
  });
  const auto a = node.exchange(0.25, {0.02}, {0.3});
  const FrameValues command = seen.get();
  EXPECT_EQ(command.counter, 1);
  EXPECT_EQ(command.status, kStatusRun);
  EXPECT_EQ(command.time, 0.25);
  EXPECT_EQ(command.target_displacement[0], 0.02);
  EXPECT_EQ(command.target_velocity[0], 0.3);
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  EXPECT_EQ(a.displacement[0], 0.01);
  EXPECT_EQ(a.force[0], 1234.5);
  EXPECT_GT(a.round_trip, 0.0);
  EXPECT_LT(a.round_trip, 0.5);
  EXPECT_EQ(node.report().frames_accepted(), 1u);
  EXPECT_EQ(node.report().round_trip_last(), a.round_trip);
}

TEST(ControllerExchange, FramesFromAnyoneButThePeerAreCountedNamedAndNeverApplied) {
  const auto link = test::controller_link(47102, 47103);
  ControllerExchange node(link, settings());
  Controller controller(link);
  // The rogue knows the layout and the counter, and sends from another port of the same host.
  UdpLink rogue("127.0.0.1", 47104, "127.0.0.1", 47102);
  auto seen = controller.answer([&](const FrameValues& c) {
    rogue.send(controller.feedback(c.counter, 0.09, 99999.0));
    rogue.send({1, 2, 3});
    return Frames{controller.feedback(c.counter, 0.001, 10.0)};
  });
  const auto a = node.exchange(0.0, {0.001}, {0.0});
  seen.get();
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  EXPECT_EQ(a.displacement[0], 0.001);
  EXPECT_EQ(a.force[0], 10.0);
  EXPECT_EQ(node.report().wrong_source(), 2u);
  EXPECT_NE(node.report().last_reject().find("frame from 127.0.0.1:47104 (not the controller "
                                             "127.0.0.1:47103)"),
            std::string::npos)
      << node.report().last_reject();
}

// The peer's frame is refused: the exchange faults naming why, and counts the cause.
struct Refused {
  std::string name;
  std::function<std::vector<std::uint8_t>(Controller&, const FrameValues&)> frame;
  std::string named;
};

ControllerExchange::Answer refused_answer(int port, const Refused& r, ControllerExchange*& out,
                                          std::unique_ptr<ControllerExchange>& keep) {
  const auto link = test::controller_link(port, port + 1);
  keep = std::make_unique<ControllerExchange>(link, settings());
  out = keep.get();
  Controller controller(link);
  auto seen =
      controller.answer([&](const FrameValues& c) { return Frames{r.frame(controller, c)}; });
  const auto a = keep->exchange(0.0, {0.001}, {0.0});
  seen.get();
  return a;
}

TEST(ControllerExchange, WrongSizeNonFiniteCountersStatusAndRangeAreFaults) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Refused> cases = {
      {"wrong size",
       [](Controller& c, const FrameValues& v) {
         auto f = c.feedback(v.counter, 0.0, 0.0);
         f.pop_back();
         return f;
       },
       "has 23 bytes, the feedback frame 24"},
      {"not finite",
       [&](Controller& c, const FrameValues& v) {
         auto f = c.feedback(v.counter, 0.0, 0.0);
         std::memcpy(f.data() + 8, &nan, 8);  // the measured drift: the encoder refuses a NaN
         return f;
       },
       "not finite"},
      {"repeated",
       [](Controller& c, const FrameValues& v) { return c.feedback(v.counter - 1, 0, 0); },
       "repeats counter 0"},
      {"never sent",
       [](Controller& c, const FrameValues& v) { return c.feedback(v.counter + 5, 0, 0); },
       "echoes counter 6, never sent"},
      {"status", [](Controller& c, const FrameValues& v) { return c.feedback(v.counter, 0, 0, 3); },
       "reports status 3"},
      {"range", [](Controller& c, const FrameValues& v) { return c.feedback(v.counter, 0.2, 0); },
       "beyond the run's limits"},
  };
  int port = 47110;
  for (const Refused& r : cases) {
    ControllerExchange* node = nullptr;
    std::unique_ptr<ControllerExchange> keep;
    const auto a = refused_answer(port, r, node, keep);
    port += 2;
    EXPECT_EQ(a.outcome, Outcome::kFault) << r.name;
    EXPECT_NE(a.fault.find(r.named), std::string::npos) << r.name << ": " << a.fault;
    EXPECT_EQ(node->report().last_reject(), a.fault) << r.name;
    EXPECT_EQ(node->report().frames_accepted(), 0u) << r.name;
  }
}

TEST(ControllerExchange, CausesAreCountedApart) {
  Refused repeated{
      "repeated",
      [](Controller& c, const FrameValues& v) { return c.feedback(v.counter - 1, 0, 0); }, ""};
  ControllerExchange* node = nullptr;
  std::unique_ptr<ControllerExchange> keep;
  refused_answer(47130, repeated, node, keep);
  EXPECT_EQ(node->report().repeated_counter(), 1u);
  EXPECT_EQ(node->report().wrong_size() + node->report().non_finite() +
                node->report().unexpected_counter() + node->report().out_of_range(),
            0u);
}

TEST(ControllerExchange, ASilentControllerIsAFaultInLockstepAfterTheTimeout) {
  const auto link = test::controller_link(47132, 47133);
  ControllerExchange node(link, settings(0.05));
  Controller controller(link);  // bound, never answers
  const std::int64_t start = monotonic_ns();
  const auto a = node.exchange(0.0, {0.0}, {0.0});
  const double waited = static_cast<double>(monotonic_ns() - start) * 1e-9;
  EXPECT_EQ(a.outcome, Outcome::kFault);
  EXPECT_NE(a.fault.find("did not answer frame 1 within 50.000000 ms"), std::string::npos)
      << a.fault;
  EXPECT_GE(waited, 0.05);
  EXPECT_LT(waited, 0.5);
  EXPECT_EQ(node.report().lost(), 1u);
}

TEST(ControllerExchange, RealTimeLostFramesFaultAfterTheWindowAndLateAnswersAreCounted) {
  const auto link = test::controller_link(47134, 47135);
  ControllerExchange node(link, settings(0.02, true, 3));
  Controller controller(link);
  EXPECT_EQ(node.exchange(0.0, {0.0}, {0.0}).outcome, Outcome::kLate);  // frame 1 lost
  EXPECT_EQ(controller.take().counter, 1);
  // Frame 2: the late answer to frame 1 arrives first and is only counted; then frame 2's.
  auto seen = controller.answer([&](const FrameValues& c) {
    return Frames{controller.feedback(1, 0.5, 0.0), controller.feedback(c.counter, 0.003, 7)};
  });
  const auto a = node.exchange(0.001, {0.003}, {0.0});
  seen.get();
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  EXPECT_EQ(a.displacement[0], 0.003);
  EXPECT_EQ(node.report().late(), 1u);
  EXPECT_EQ(node.exchange(0.0, {0.0}, {0.0}).outcome, Outcome::kLate);
  EXPECT_EQ(node.exchange(0.0, {0.0}, {0.0}).outcome, Outcome::kLate);
  const auto third = node.exchange(0.0, {0.0}, {0.0});
  EXPECT_EQ(third.outcome, Outcome::kFault);
  EXPECT_NE(third.fault.find("(3 lost in a row)"), std::string::npos) << third.fault;
  EXPECT_EQ(node.report().lost(), 4u);
}

TEST(ControllerExchange, HoldAndStopReachTheControllerAsStatusInACommandFrame) {
  const auto link = test::controller_link(47136, 47137);
  ControllerExchange node(link, settings());
  Controller controller(link);
  ASSERT_TRUE(node.send_status(kStatusHold));
  const FrameValues hold = controller.take();
  EXPECT_EQ(hold.status, kStatusHold);
  EXPECT_EQ(hold.counter, 1);
  ASSERT_TRUE(node.send_status(kStatusStop));
  const FrameValues stop = controller.take();
  EXPECT_EQ(stop.status, kStatusStop);
  EXPECT_EQ(stop.counter, 2);
  EXPECT_EQ(node.report().frames_sent(), 2u);
}

TEST(ControllerExchange, ABadLinkIsRefusedNamingIt) {
  EXPECT_THROW(ControllerExchange(test::controller_link(47138, 70000), settings()),
               std::runtime_error);
  auto link = test::controller_link(47138, 47139);
  link.set_local_address("10.0.0.300");
  EXPECT_THROW(ControllerExchange(link, settings()), std::runtime_error);
  link = test::controller_link(47138, 47139);
  link.mutable_feedback()->mutable_fields(0)->set_role(config::FrameField::MEASURED_FORCE);
  EXPECT_THROW(ControllerExchange(link, settings()), std::invalid_argument);
}

}  // namespace
}  // namespace rths::controller_node
