// The hold of the judged exchange (controller_node/controller_hold.cpp), the test playing the
// controller over an in-process link (no ports), or over real UDP sockets on 127.0.0.1 where the
// socket is what is tested (ICMP errors, a flood before the link opens, ports 47400-47449): only a status-HOLD echo of a HOLD frame that left
// ends the hold (a wrong echo, a replayed one, the echo of a run frame, a status 1 sent before
// any HOLD frame each leave it on, counted and named); a restarted controller is held where it
// measures itself, never where the rig was before; every HOLD frame, answer and STOP is logged,
// at most one HOLD frame per dt; ICMP errors on the socket are counted and never a fault; lost
// and late frames are located.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <thread>

#include <google/protobuf/text_format.h>

#include "controller_node/controller_exchange.h"
#include "in_process_link.h"
#include "link_text.h"
#include "test_controller.h"

namespace rths::controller_node {
namespace {

using Outcome = ControllerExchange::Outcome;

using Controller = test::TestController;

ExchangeSettings settings(double jump_floor = 0.0) {
  ExchangeSettings s;
  s.actuators = 1;
  s.dt = 0.001;
  s.reply_timeout = 0.5;
  s.max_drift = 0.2;
  s.max_force = 1e6;
  s.jump_floor = jump_floor;
  s.tracking_lag = 0.05;  // the node's default: the adaptive tracking bound on
  s.hold_time = 0.3;
  return s;
}

using test::await_answer;

// Steps the hold until it ends or `seconds` pass; true when it ended.
bool hold_for(ControllerExchange& node, double seconds) {
  const std::int64_t until = monotonic_ns() + static_cast<std::int64_t>(seconds * 1e9);
  while (monotonic_ns() < until) {
    if (node.hold_step(monotonic_ns())) return true;
    node.wait(monotonic_ns() + 200'000);
  }
  return node.hold_step(monotonic_ns());
}

// The next HOLD frame the node sends, stepping it meanwhile.
FrameValues next_hold_frame(ControllerExchange& node, Controller& controller) {
  FrameValues v;
  const std::int64_t until = monotonic_ns() + 200'000'000;
  while (v.counter == 0 && monotonic_ns() < until) {
    node.hold_step(monotonic_ns());
    v = controller.take(0.0005);
  }
  return v;
}

// A node and the controller answering it. run(frames, drift): frames answered on target, the
// target ramping to `drift` m over 20 frames, then steady (target velocity 0).
struct Drill {
  config::ControllerLink link;
  test::InProcessLinkPair pair;
  ControllerExchange node;
  Controller controller;
  explicit Drill(const ExchangeSettings& s)
      : link(test::controller_link(47448, 47449)),
        pair(test::real_clock()),
        node(link, s, pair.node_end()),
        controller(link, pair.controller(), test::real_clock()) {}
  void run(int frames, double drift) {
    for (int k = 1; k <= frames; ++k) {
      const double target = drift * std::min(1.0, static_cast<double>(k) / 20.0);
      node.send_command(k, k * 0.001, {target}, {k <= 20 ? drift / 0.02 : 0.0});
      controller.answer(controller.take().counter, target, 1e4 * target);
      ASSERT_EQ(await_answer(node).outcome, Outcome::kAnswered) << "frame " << k;
    }
  }
};

TEST(ControllerHold, OnlyTheRigsStatusHoldEchoOfASentHoldFrameEndsTheHold) {
  Drill d(settings());
  d.run(30, 0.005);
  // Sent before any HOLD frame: a status 1 echoing the counter the first HOLD frame will take.
  d.controller.answer(31, 0.005, 50.0, kStatusHold);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  d.node.begin_hold(monotonic_ns());
  const FrameValues first = next_hold_frame(d.node, d.controller);
  ASSERT_EQ(first.counter, 31);
  EXPECT_EQ(first.status, kStatusHold);
  EXPECT_NEAR(first.target_displacement[0], 0.005, 1e-12);
  d.controller.answer(9449, 0.005, 50.0, kStatusHold);  // a wrong echo: never sent
  d.controller.answer(17, 0.005, 50.0, kStatusHold);    // a replayed echo of an answered run frame
  d.controller.answer(30, 0.005, 50.0, kStatusHold);    // the echo of a run frame
  EXPECT_FALSE(hold_for(d.node, 0.02));
  const runtime::ControllerReport& r = d.node.report();
  EXPECT_EQ(r.hold_rejected(), 4u) << r.last_hold_reject();
  EXPECT_LT(r.held_after(), 0.0);
  std::vector<std::string> verdicts;
  for (const auto& e : r.hold_log())
    if (e.kind() == runtime::HoldEntry::ANSWER) verdicts.push_back(e.verdict());
  ASSERT_EQ(verdicts.size(), 4u);
  EXPECT_NE(verdicts[0].find("echoes frame 31, never sent"), std::string::npos) << verdicts[0];
  EXPECT_NE(verdicts[1].find("echoes frame 9449, never sent"), std::string::npos) << verdicts[1];
  EXPECT_NE(verdicts[2].find("echoes frame 17, a frame sent before the hold"), std::string::npos)
      << verdicts[2];
  EXPECT_NE(verdicts[3].find("echoes frame 30, a frame sent before the hold"), std::string::npos)
      << verdicts[3];
  // The rig's own answer to a HOLD frame, status 1: held.
  const FrameValues hold = next_hold_frame(d.node, d.controller);
  ASSERT_GT(hold.counter, 31);
  d.controller.answer(hold.counter, 0.005, 50.0, kStatusHold);
  EXPECT_TRUE(hold_for(d.node, 0.2));
  EXPECT_GT(d.node.report().held_after(), 0.0);
  EXPECT_EQ(d.node.report().hold_log().rbegin()->verdict(), "held");
  ASSERT_TRUE(d.node.send_stop());
  EXPECT_EQ(d.node.report().hold_log().rbegin()->kind(), runtime::HoldEntry::SENT_STOP);
}

TEST(ControllerHold, AStatusZeroEchoIsHoldingAndAHoldNeverEndedStopsAtTheHoldTime) {
  Drill d(settings());
  d.run(5, 0.002);
  d.node.begin_hold(monotonic_ns());
  const FrameValues hold = next_hold_frame(d.node, d.controller);
  d.controller.answer(hold.counter, 0.002, 20.0, kStatusRun);   // still settling
  d.controller.answer(hold.counter, 0.002, 20.0, kStatusHold);  // a second answer to the same
  const std::int64_t start = monotonic_ns();
  EXPECT_TRUE(hold_for(d.node, 1.0));
  EXPECT_GE(static_cast<double>(monotonic_ns() - start) * 1e-9, 0.2);  // the hold time, not held
  const runtime::ControllerReport& r = d.node.report();
  EXPECT_LT(r.held_after(), 0.0);
  EXPECT_EQ(r.hold_rejected(), 1u);
  EXPECT_NE(r.last_hold_reject().find("repeats the answer to HOLD frame"), std::string::npos)
      << r.last_hold_reject();
  // HOLD frames one dt apart at most: never two within 0.9 dt.
  double previous = -1.0;
  int sent = 0;
  for (const auto& e : r.hold_log()) {
    if (e.kind() != runtime::HoldEntry::SENT_HOLD) continue;
    if (previous >= 0) {
      EXPECT_GE(e.time() - previous, 0.0009) << "HOLD frame " << e.counter();
    }
    previous = e.time();
    ++sent;
  }
  EXPECT_EQ(static_cast<std::uint64_t>(sent), r.hold_frames());
}

// A controller reboots at `drift`: its echo stays right, its state is lost (it measures 0). The
// default jump check HOLDs; the HOLD frames carry 0 (where the rebooted rig is), not `drift`.
void reboot_at(double drift) {
  Drill d(settings(2e-4));
  d.run(100, drift);  // at rest at `drift` for the last 80 frames
  d.node.send_command(101, 0.101, {drift}, {0.0});
  d.controller.answer(d.controller.take().counter, 0.0, 0.0);
  const auto fault = await_answer(d.node);
  ASSERT_EQ(fault.outcome, Outcome::kFault) << "a reboot at " << drift * 1e3 << " mm";
  EXPECT_NE(fault.fault.find("a restarted controller or a sensor fault"), std::string::npos)
      << fault.fault;
  d.node.begin_hold(monotonic_ns());
  for (int k = 0; k < 3; ++k) {
    const FrameValues hold = next_hold_frame(d.node, d.controller);
    ASSERT_EQ(hold.status, kStatusHold);
    EXPECT_EQ(hold.target_displacement[0], 0.0) << "a reboot at " << drift * 1e3 << " mm";
    d.controller.answer(hold.counter, 0.0, 0.0, kStatusRun);
  }
  EXPECT_FALSE(d.node.report().restart().empty());
}

TEST(ControllerHold, ARebootAtAnyDriftAboveTheFloorIsHeldWhereTheRebootedRigIs) {
  reboot_at(0.001);
  reboot_at(0.004);
  reboot_at(0.010);
}

TEST(ControllerHold, ARigFollowingItsTargetsIsNeverAJump) {
  Drill d(settings(2e-4));
  // 2 Hz, 20 mm: 0.25 m/s peak; answers lag by 14 frames (a 14 ms plant).
  const auto target = [](int k) { return 0.02 * std::sin(2 * M_PI * 2.0 * k * 0.001); };
  const auto speed = [](int k) {
    return 0.02 * 2 * M_PI * 2.0 * std::cos(2 * M_PI * 2.0 * k * 0.001);
  };
  for (int k = 1; k <= 600; ++k) {
    d.node.send_command(k, k * 0.001, {target(k)}, {speed(k)});
    d.controller.answer(d.controller.take().counter, target(std::max(0, k - 14)), 0.0);
    const auto a = await_answer(d.node);
    ASSERT_EQ(a.outcome, Outcome::kAnswered) << "frame " << k << ": " << a.fault;
  }
}

TEST(ControllerHold, AChangedControllerEpochIsARestartHeldWhereItMeasures) {
  const std::string epoch_field =
      "feedback { fields { name: \"counter\" role: COUNTER type: U32 } "
      "fields { name: \"boot\" role: CONTROLLER_EPOCH type: U32 } "
      "fields { name: \"measured\" role: MEASURED_DISPLACEMENT } "
      "fields { name: \"force\" role: MEASURED_FORCE } "
      "fields { name: \"task_time\" role: DIAGNOSTIC unit: \"s\" min: 0 max: 0.0008 } }";
  config::ControllerLink link = test::controller_link(47448, 47449);
  link.clear_feedback();
  google::protobuf::TextFormat::MergeFromString(epoch_field, &link);
  test::InProcessLinkPair pair(test::real_clock());
  ControllerExchange node(link, settings(), pair.node_end());
  DatagramLink& rig = pair.controller();
  const auto answer = [&](std::int64_t counter, std::int64_t epoch, double drift, double task) {
    FrameValues v;
    v.counter = counter;
    v.epoch = epoch;
    v.measured_displacement = {drift};
    v.measured_force = {0.0};
    v.diagnostics = {task};
    std::vector<std::uint8_t> bytes;
    Datagram d;
    while (!rig.try_receive(d)) rig.wait(monotonic_ns() + 100'000'000);
    ASSERT_TRUE(encode(link.feedback(), v, bytes));
    rig.send(bytes.data(), bytes.size());
  };
  node.send_command(1, 0.001, {0.003}, {0.0});
  answer(1, 7, 0.003, 0.0004);
  auto a = await_answer(node);
  ASSERT_EQ(a.outcome, Outcome::kAnswered) << a.fault;
  ASSERT_EQ(a.diagnostics->size(), 1u);
  EXPECT_DOUBLE_EQ((*a.diagnostics)[0], 0.0004);
  node.send_command(2, 0.002, {0.003}, {0.0});
  answer(2, 8, 0.0029, 0.0004);  // a small move, but a new epoch
  a = await_answer(node);
  ASSERT_EQ(a.outcome, Outcome::kFault);
  EXPECT_NE(a.fault.find("restarted: its epoch went from 7 to 8"), std::string::npos) << a.fault;
  node.begin_hold(monotonic_ns());
  Datagram d;
  FrameValues hold;
  for (int i = 0; i < 200 && hold.counter == 0; ++i) {
    node.hold_step(monotonic_ns());
    if (rig.try_receive(d))
      decode(link.command(), d.bytes.data(), d.size, 1, hold);
    else
      rig.wait(monotonic_ns() + 500'000);
  }
  ASSERT_EQ(hold.status, kStatusHold);
  EXPECT_EQ(hold.target_displacement[0], 0.0029);
}

TEST(ControllerHold, ADiagnosticOutsideItsBoundsHoldsNamingTheChannel) {
  config::ControllerLink link = test::controller_link(47448, 47449);
  link.clear_feedback();
  google::protobuf::TextFormat::MergeFromString(
      "feedback { fields { name: \"counter\" role: COUNTER type: U32 } "
      "fields { name: \"measured\" role: MEASURED_DISPLACEMENT } "
      "fields { name: \"force\" role: MEASURED_FORCE } "
      "fields { name: \"supply_pressure\" role: DIAGNOSTIC unit: \"MPa\" scale: 1e6 min: 1.5e7 "
      "max: 2.2e7 } }",
      &link);
  test::InProcessLinkPair pair(test::real_clock());
  ControllerExchange node(link, settings(), pair.node_end());
  Controller rig(link, pair.controller(), test::real_clock());
  node.send_command(1, 0.001, {0.0}, {0.0});
  rig.take();
  FrameValues v;
  v.counter = 1;
  v.measured_displacement = {0.0};
  v.measured_force = {0.0};
  v.diagnostics = {9e6};  // 9 MPa: the supply dropped
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encode(link.feedback(), v, bytes));
  rig.end.send(bytes.data(), bytes.size());
  const auto a = await_answer(node);
  ASSERT_EQ(a.outcome, Outcome::kFault);
  EXPECT_NE(a.fault.find("a diagnostic supply_pressure of 9e+06"), std::string::npos) << a.fault;
  EXPECT_NE(a.fault.find("outside its bounds [1.5e+07, 2.2e+07]"), std::string::npos) << a.fault;
}

TEST(ControllerHold, ICMPErrorsOnTheSocketAreCountedNeverAFault) {
  // No controller listens: every frame draws a port unreachable, reported on the next send.
  const auto link = test::controller_link(47416, 47417);
  ControllerExchange node(link, settings());
  for (int k = 1; k <= 20; ++k) {
    ASSERT_TRUE(node.send_command(k, k * 0.001, {0.0}, {0.0})) << node.fault();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    EXPECT_NE(node.next(monotonic_ns()).outcome, Outcome::kFault);
  }
  const runtime::ControllerReport& r = node.report();
  EXPECT_GT(r.icmp_errors(), 0u);
  EXPECT_NE(r.last_icmp_error().find("errno 111"), std::string::npos) << r.last_icmp_error();
}

TEST(ControllerHold, AFloodRunningBeforeTheLinkOpensNeverReachesItsJudge) {
  // A sender floods the node's port from another port while links are opened on it again and
  // again: a datagram that lands between bind and connect is drained unread, never judged as a
  // frame from a wrong source (which fails a clean run at its end).
  const int port = 47418;
  std::atomic<bool> flooding{true};
  std::thread flood([&] {
    const int fd = socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const char junk[64] = {};
    while (flooding.load())
      sendto(fd, junk, sizeof junk, MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&to),
             sizeof to);
    close(fd);
  });
  std::uint64_t drained = 0;
  for (int i = 0; i < 200; ++i) {
    ControllerExchange node(test::controller_link(port, port + 1), settings());
    node.next(monotonic_ns());
    EXPECT_EQ(node.report().wrong_source(), 0u) << "link " << i;
    drained += node.report().drained_before_connect();
  }
  flooding = false;
  flood.join();
  std::printf("datagrams drained between bind and connect over 200 links: %llu\n",
              static_cast<unsigned long long>(drained));
}

TEST(ControllerHold, LostAndLateFramesAreLocatedAndALateControllerIsCalledLate) {
  ExchangeSettings s = settings();
  s.reply_timeout = 0.01;
  s.real_time = true;
  s.lost_window = 1;
  Drill d(s);
  d.run(3, 0.001);
  for (int k = 4; k <= 6; ++k) {
    d.node.send_command(k, k * 0.001, {0.001}, {0.0});
    const FrameValues c = d.controller.take();
    std::this_thread::sleep_for(std::chrono::milliseconds(12));  // past the reply timeout
    d.controller.answer(c.counter, 0.001, 10.0);
    const auto a = await_answer(d.node, 0.03);
    ASSERT_NE(a.outcome, Outcome::kAnswered) << "frame " << k;
  }
  d.node.send_command(7, 0.007, {0.001}, {0.0});  // never answered
  const auto a = await_answer(d.node, 0.5);
  ASSERT_EQ(a.outcome, Outcome::kFault);
  EXPECT_NE(a.fault.find("answers late: frame 7 (step 7) unanswered"), std::string::npos)
      << a.fault;
  const runtime::ControllerReport& r = d.node.report();
  EXPECT_GT(r.round_trip_max(), 0.01);  // the late answers' round trips count
  int located = 0;
  for (const auto& m : r.late_frames()) {
    EXPECT_EQ(m.step(), m.counter());
    EXPECT_GT(m.round_trip(), 0.01);
    ++located;
  }
  for (const auto& m : r.lost_frames()) EXPECT_EQ(m.step(), m.counter());
  EXPECT_EQ(static_cast<std::uint64_t>(located), r.late());
  EXPECT_EQ(r.lost_frames(r.lost_frames_size() - 1).counter(), 7);
}

}  // namespace
}  // namespace rths::controller_node
