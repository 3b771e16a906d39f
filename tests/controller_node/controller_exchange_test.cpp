// The judged exchange with a controller: the test plays the controller (reads command frames,
// sends feedback frames as told) over an in-process link (no ports), on a manual clock where a
// test is about time (a stale frame, lost frames, the hold time), so that it judges the exchange
// and not the machine's scheduling. What needs the real socket runs on UDP on 127.0.0.1 (ports
// 47100-47149): the first exchange again, a rogue socket on another port, and a bad address.
// Several frames may be in flight; every rejected frame is counted by cause and named, none is
// applied; the hold repeats HOLD frames at the measured position until the controller says held.
#include "controller_node/controller_exchange.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "in_process_link.h"
#include "link_text.h"
#include "test_controller.h"

namespace rths::controller_node {
namespace {

using Outcome = ControllerExchange::Outcome;

using Controller = test::TestController;

ExchangeSettings settings(double timeout = 0.5, bool real_time = false, int window = 1) {
  ExchangeSettings s;
  s.actuators = 1;
  s.dt = 0.001;
  s.reply_timeout = timeout;
  s.real_time = real_time;
  s.lost_window = window;
  s.max_drift = 0.1;
  s.max_force = 1e5;
  s.hold_time = 0.2;
  return s;
}

using test::await_answer;

// A clock that moves only when told (ns).
class ManualClock final : public runtime::PacingClock {
 public:
  std::int64_t now_ns() override { return now_; }
  void sleep_until_ns(std::int64_t deadline) override { now_ = std::max(now_, deadline); }
  void advance(double seconds) { now_ += static_cast<std::int64_t>(seconds * 1e9); }

 private:
  std::int64_t now_ = 1'000'000'000;
};

// An exchange and the test's controller on an in-process link, on `clock` (default: the real
// CLOCK_MONOTONIC). The link's addresses are never bound.
struct InProcess {
  explicit InProcess(const ExchangeSettings& s, runtime::PacingClock& clock = test::real_clock())
      : link(test::controller_link(47198, 47199)),
        pair(clock),
        node(link, s, pair.node_end(), &clock),
        controller(link, pair.controller(), clock) {}
  config::ControllerLink link;
  test::InProcessLinkPair pair;
  ControllerExchange node;
  Controller controller;
};

// The same exchange on the in-process link and on real UDP sockets.
void answer_echoing_the_counter(ControllerExchange& node, Controller& controller) {
  ASSERT_TRUE(node.send_command(7, 0.25, {0.02}, {0.3}));
  const FrameValues command = controller.take();
  EXPECT_EQ(command.counter, 1);
  EXPECT_EQ(command.status, kStatusRun);
  EXPECT_EQ(command.time, 0.25);
  EXPECT_EQ(command.target_displacement[0], 0.02);
  EXPECT_EQ(command.target_velocity[0], 0.3);
  controller.send(controller.feedback(1, 0.01, 1234.5));
  const auto a = await_answer(node);
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  EXPECT_EQ(a.step, 7);
  EXPECT_EQ((*a.displacement)[0], 0.01);
  EXPECT_EQ((*a.force)[0], 1234.5);
  EXPECT_GT(a.round_trip, 0.0);
  EXPECT_LT(a.round_trip, 0.5);
  EXPECT_EQ(node.report().frames_accepted(), 1u);
  EXPECT_EQ(node.report().round_trip_last(), a.round_trip);
  EXPECT_EQ(node.report().round_trip_median(), a.round_trip);
}

TEST(ControllerExchange, AnAnswerEchoingTheCounterIsAppliedForItsStepWithItsRoundTrip) {
  InProcess in_process(settings());
  answer_echoing_the_counter(in_process.node, in_process.controller);
  const auto link = test::controller_link(47100, 47101);
  ControllerExchange node(link, settings());
  Controller controller(link);
  answer_echoing_the_counter(node, controller);
}

TEST(ControllerExchange, SeveralFramesInFlightAreAnsweredByTheirCounters) {
  InProcess bench(settings());
  ControllerExchange& node = bench.node;
  Controller& controller = bench.controller;
  for (int step = 1; step <= 3; ++step)
    ASSERT_TRUE(node.send_command(step, step * 0.001, {step * 1e-4}, {0.0}));
  EXPECT_EQ(node.report_as_is().in_flight(), 3u);
  for (int k = 1; k <= 3; ++k) {
    const FrameValues c = controller.take();
    controller.send(controller.feedback(c.counter, c.target_displacement[0], 10.0 * k));
  }
  for (int step = 1; step <= 3; ++step) {
    const auto a = await_answer(node);
    ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
    EXPECT_EQ(a.step, step);
    EXPECT_EQ((*a.displacement)[0], step * 1e-4);
  }
  EXPECT_EQ(await_answer(node, 0.05).outcome, Outcome::kNone);
}

TEST(ControllerExchange, AnAnswerOlderThanTheNewestAnsweredIsLateAndNeverApplied) {
  InProcess bench(settings());
  ControllerExchange& node = bench.node;
  Controller& controller = bench.controller;
  node.send_command(1, 0.001, {0.001}, {0.0});
  node.send_command(2, 0.002, {0.002}, {0.0});
  controller.take();
  controller.take();
  controller.send(controller.feedback(2, 0.002, 2.0));
  controller.send(controller.feedback(1, 0.001, 1.0));
  const auto a = await_answer(node);
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  EXPECT_EQ(a.step, 2);
  EXPECT_EQ(await_answer(node, 0.05).outcome, Outcome::kNone);
  EXPECT_EQ(node.report().late(), 1u);
}

TEST(ControllerExchange, TheKernelDropsFramesFromAnotherPortBeforeTheyTakeBufferRoom) {
  const auto link = test::controller_link(47106, 47107);
  ControllerExchange node(link, settings());
  Controller controller(link);
  // The rogue knows the layout and the counter, and sends from another port of the same host:
  // a flood of the largest datagrams, then a frame that would be applied.
  UdpLink rogue("127.0.0.1", 47108, "127.0.0.1", 47106);
  std::vector<std::uint8_t> big(65000, 0xAB);
  node.send_command(1, 0.0, {0.001}, {0.0});
  controller.take();
  for (int i = 0; i < 2000; ++i) rogue.send(big.data(), big.size());
  const auto forged = controller.feedback(1, 0.09, 99999.0);
  rogue.send(forged.data(), forged.size());
  controller.send(controller.feedback(1, 0.001, 10.0));
  const auto a = await_answer(node);
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  EXPECT_EQ((*a.displacement)[0], 0.001);
  EXPECT_EQ((*a.force)[0], 10.0);
  EXPECT_EQ(node.report().wrong_source(), 0u);
}

struct Refused {
  std::string name;
  std::function<std::vector<std::uint8_t>(Controller&, const FrameValues&)> frame;
  std::string named;
};

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
       "repeats counter 1 (already answered)"},
      {"never sent",
       [](Controller& c, const FrameValues& v) { return c.feedback(v.counter + 5, 0, 0); },
       "echoes counter 7, never sent"},
      {"status", [](Controller& c, const FrameValues& v) { return c.feedback(v.counter, 0, 0, 3); },
       "reports status 3"},
      {"range", [](Controller& c, const FrameValues& v) { return c.feedback(v.counter, 0.2, 0); },
       "beyond the run's limit of 0.100000 m"},
  };
  for (const Refused& r : cases) {
    InProcess bench(settings());
    ControllerExchange& node = bench.node;
    Controller& controller = bench.controller;
    // Frame 1 answered well, then frame 2 answered as the case says.
    node.send_command(1, 0.001, {0.0}, {0.0});
    controller.send(controller.feedback(controller.take().counter, 0.0, 0.0));
    ASSERT_EQ(await_answer(node).outcome, Outcome::kAnswered) << r.name;
    node.send_command(2, 0.002, {0.0}, {0.0});
    controller.send(r.frame(controller, controller.take()));
    const auto a = await_answer(node);
    EXPECT_EQ(a.outcome, Outcome::kFault) << r.name;
    EXPECT_NE(a.fault.find(r.named), std::string::npos) << r.name << ": " << a.fault;
    EXPECT_EQ(node.report().last_reject(), a.fault) << r.name;
    EXPECT_EQ(node.report().frames_accepted(), 1u) << r.name;
  }
}

// The rig answers plausibly for `good` frames, then with `last`; what the node makes of it.
ControllerExchange::Answer after_good_answers(ExchangeSettings s, int good, double last_drift,
                                              double last_force,
                                              ControllerExchange::Answer* last_good = nullptr) {
  InProcess bench(s);
  ControllerExchange& node = bench.node;
  Controller& controller = bench.controller;
  for (int step = 1; step <= good + 1; ++step) {
    const double target = 0.001 * step;
    node.send_command(step, step * 0.001, {target}, {1.0});
    const FrameValues c = controller.take();
    const bool is_last = step == good + 1;
    controller.send(controller.feedback(c.counter, is_last ? last_drift : target * 0.99,
                                        is_last ? last_force : 1000.0 * target));
    auto a = await_answer(node);
    if (is_last || a.outcome != Outcome::kAnswered) return a;
    if (last_good) *last_good = a;
  }
  return {};
}

TEST(ControllerExchange, AMeasurementMovingFasterThanTheRigCouldIsImplausible) {
  ExchangeSettings s = settings();
  s.max_measured_rate = 2.0;  // m/s
  s.max_force_rate = 2e3;     // N/s; the good answers move 1 N per ms = 1e3 N/s
  // A rebooted controller: its echo is right, its state is lost (drift and force back to 0).
  const auto force_jump = after_good_answers(s, 5, 0.0059, 0.0);
  EXPECT_EQ(force_jump.outcome, Outcome::kFault);
  EXPECT_NE(force_jump.fault.find("implausible measurement: the measured force of actuator 1 "
                                  "(frame 6, step 6) moved -5.0 N in 1.000 ms"),
            std::string::npos)
      << force_jump.fault;
  const auto drift_jump = after_good_answers(s, 5, 0.0, 6.0);
  EXPECT_EQ(drift_jump.outcome, Outcome::kFault);
  EXPECT_NE(drift_jump.fault.find("the measured drift of actuator 1 (frame 6, step 6) moved"),
            std::string::npos)
      << drift_jump.fault;
  EXPECT_NE(drift_jump.fault.find("bound max_measured_rate 2.000 m/s"), std::string::npos)
      << drift_jump.fault;
  // Within both bounds: answered.
  EXPECT_EQ(after_good_answers(s, 5, 0.0060, 6.0).outcome, Outcome::kAnswered);
}

TEST(ControllerExchange, ATrackingErrorBeyondItsBoundForItsStepsIsAFault) {
  ExchangeSettings s = settings();
  s.max_tracking_error = 0.0005;  // m
  s.tracking_error_steps = 3;
  InProcess bench(s);
  ControllerExchange& node = bench.node;
  Controller& controller = bench.controller;
  ControllerExchange::Answer a;
  for (int step = 1; step <= 3; ++step) {
    node.send_command(step, step * 0.001, {0.002}, {0.0});
    controller.send(controller.feedback(controller.take().counter, 0.0, 0.0));  // stuck at 0
    a = await_answer(node);
    if (step < 3) EXPECT_EQ(a.outcome, Outcome::kAnswered) << step << ": " << a.fault;
  }
  EXPECT_EQ(a.outcome, Outcome::kFault);
  EXPECT_NE(a.fault.find("tracking error: actuator 1 (frame 3, step 3) measured 0.000 mm for "
                         "a target of 2.000 mm"),
            std::string::npos)
      << a.fault;
  EXPECT_EQ(node.report().implausible(), 1u);
}

TEST(ControllerExchange, ASilentControllerIsAFaultInLockstepOnceTheFrameIsStale) {
  ManualClock clock;
  InProcess bench(settings(0.05), clock);  // the controller never answers
  ControllerExchange& node = bench.node;
  node.send_command(1, 0.0, {0.0}, {0.0});
  EXPECT_EQ(node.next(clock.now_ns()).outcome, Outcome::kNone);  // nothing waits
  clock.advance(0.0499);
  EXPECT_EQ(node.next(clock.now_ns()).outcome, Outcome::kNone);  // not stale yet
  clock.advance(0.0002);
  const auto a = node.next(clock.now_ns());
  EXPECT_EQ(a.outcome, Outcome::kFault);
  EXPECT_NE(a.fault.find("did not answer frame 1 (step 1) within 50 ms"), std::string::npos)
      << a.fault;
  EXPECT_EQ(node.report().lost(), 1u);
}

TEST(ControllerExchange, RealTimeLostFramesFaultAfterTheWindowAndLateAnswersAreCounted) {
  ManualClock clock;
  InProcess bench(settings(0.02, true, 3), clock);
  ControllerExchange& node = bench.node;
  Controller& controller = bench.controller;
  node.send_command(1, 0.001, {0.0}, {0.0});
  EXPECT_EQ(controller.take().counter, 1);
  clock.advance(0.03);
  EXPECT_EQ(node.next(clock.now_ns()).outcome, Outcome::kNone);  // frame 1 lost, 1 in a row
  // The late answer to frame 1 is only counted; frame 2's is applied.
  node.send_command(2, 0.002, {0.003}, {0.0});
  controller.take();
  controller.send(controller.feedback(1, 0.05, 0.0));
  controller.send(controller.feedback(2, 0.003, 7));
  const auto a = await_answer(node);
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  EXPECT_EQ((*a.displacement)[0], 0.003);
  EXPECT_EQ(node.report().late(), 1u);
  for (int step = 3; step <= 5; ++step) node.send_command(step, 0.001 * step, {0.0}, {0.0});
  EXPECT_EQ(node.next(clock.now_ns()).outcome, Outcome::kNone);  // none stale yet
  clock.advance(0.03);
  const auto third = node.next(clock.now_ns());
  EXPECT_EQ(third.outcome, Outcome::kFault);
  EXPECT_NE(third.fault.find("(3 lost in a row)"), std::string::npos) << third.fault;
  EXPECT_EQ(node.report().lost(), 4u);
}

TEST(ControllerExchange, TheHoldRepeatsHoldFramesAtTheMeasuredPositionUntilHeldThenStops) {
  InProcess bench(settings());
  ControllerExchange& node = bench.node;
  Controller& controller = bench.controller;
  node.send_command(1, 0.001, {0.004}, {0.2});
  controller.send(controller.feedback(controller.take().counter, 0.0035, 50.0));
  ASSERT_EQ(await_answer(node).outcome, Outcome::kAnswered);
  node.send_command(2, 0.002, {0.0045}, {0.2});  // the newest target, never reached
  controller.take();
  node.begin_hold(monotonic_ns());
  // The node is stepped while the controller waits for each HOLD frame: a late wake-up of this
  // test must not skip the steps that send the frame it waits for.
  const auto next_frame = [&] {
    FrameValues v;
    const std::int64_t until = monotonic_ns() + 100'000'000;
    while (v.target_displacement.empty() && monotonic_ns() < until) {
      node.hold_step(monotonic_ns());
      v = controller.take(0.0005);
    }
    return v;
  };
  for (int k = 0; k < 3; ++k) {
    const FrameValues hold = next_frame();
    ASSERT_EQ(hold.target_displacement.size(), 1u) << "no HOLD frame " << k << " in 100 ms";
    EXPECT_EQ(hold.status, kStatusHold) << k;
    EXPECT_EQ(hold.target_displacement[0], 0.0035) << k;  // where the specimen was measured
    EXPECT_EQ(hold.target_velocity[0], 0.0) << k;
  }
  EXPECT_GE(node.report().hold_frames(), 3u);
  EXPECT_LT(node.report().held_after(), 0.0);
  // The controller holds: it answers a HOLD frame it received with status 1 (only an echo of a
  // HOLD frame sent ends the hold: controller_hold_test.cpp).
  const FrameValues held = next_frame();
  ASSERT_EQ(held.status, kStatusHold);
  controller.send(controller.feedback(held.counter, 0.0035, 0.0, kStatusHold));
  bool done = false;
  for (int i = 0; i < 1000 && !done; ++i) {
    node.wait(monotonic_ns() + 1'000'000);
    done = node.hold_step(monotonic_ns());
  }
  EXPECT_TRUE(done);
  EXPECT_GT(node.report().held_after(), 0.0);
  EXPECT_LT(node.report().held_after(), 0.2);
  ASSERT_TRUE(node.send_stop());
  FrameValues stop;
  do stop = controller.take(0.5);
  while (stop.counter != 0 && stop.status == kStatusHold);
  EXPECT_EQ(stop.status, kStatusStop);
  EXPECT_EQ(stop.target_displacement[0], 0.0035);
}

TEST(ControllerExchange, AControllerThatNeverSaysHeldIsStoppedAfterTheHoldTime) {
  ManualClock clock;
  InProcess bench(settings(), clock);  // hold_time 0.2 s, dt 1 ms
  ControllerExchange& node = bench.node;
  const std::int64_t start = clock.now_ns();
  node.begin_hold(start);
  bool done = false;
  for (int ticks = 0; !done && ticks < 10000; ++ticks) {
    clock.advance(0.0001);
    done = node.hold_step(clock.now_ns());
  }
  ASSERT_TRUE(done);
  const double held_for = static_cast<double>(clock.now_ns() - start) * 1e-9;
  EXPECT_GE(held_for, 0.2);
  EXPECT_LT(held_for, 0.2002);
  // One per dt (1 ms) for the first 50, then one per 10 dt: 50 + 15 in 200 ms.
  EXPECT_GE(node.report().hold_frames(), 64u);
  EXPECT_LE(node.report().hold_frames(), 66u);
  EXPECT_LT(node.report().held_after(), 0.0);
}

TEST(ControllerExchange, ABadLinkIsRefusedNamingIt) {
  EXPECT_THROW(ControllerExchange(test::controller_link(47146, 70000), settings()),
               std::runtime_error);
  auto link = test::controller_link(47146, 47147);
  link.set_local_address("10.0.0.300");
  EXPECT_THROW(ControllerExchange(link, settings()), std::runtime_error);
  link = test::controller_link(47146, 47147);
  link.mutable_feedback()->mutable_fields(0)->set_role(config::FrameField::MEASURED_FORCE);
  EXPECT_THROW(ControllerExchange(link, settings()), std::invalid_argument);
  ExchangeSettings s = settings();
  s.max_force_rate = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ControllerExchange(test::controller_link(47146, 47147), s), std::invalid_argument);
}

}  // namespace
}  // namespace rths::controller_node
