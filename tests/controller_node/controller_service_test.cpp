// The controller node's service as the coordinator sees it (messages in, messages out), with the
// test as its controller on real UDP sockets on 127.0.0.1: a COMMAND only sends its frame (no
// reply on the command's thread); the answer thread's take_answers() turns answers into FEEDBACK
// for the step they answer and a refused frame into a HOLD naming the cause and HOLD frames to
// the controller; the link report goes up in the heartbeat; STOP reaches the controller after
// the hold, and the final heartbeat only then. UDP ports 47160-47169.
#include "controller_node/controller_service.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "../runtime/test_support.h"
#include "link_text.h"
#include "runtime/node/schema.h"

namespace rths::controller_node {
namespace {

constexpr const char* kRunId = "controller-service-test";

runtime::Assign assign(int node_port, int peer_port, const std::string& deployment_extra,
                       const std::string& link_extra = "reply_timeout_ms: 100") {
  const config::Study study = study::parse_study(
      test::paper_frame_study(
          0.5, "deployment { nodes { id: 2 kind: CONTROLLER controller { " +
                   test::controller_link_text(node_port, peer_port, link_extra) +
                   " } } limits { max_displacement: 0.5 } " + deployment_extra + " }"),
      "test");
  runtime::Assign a;
  a.set_schema_version(runtime::kSchemaVersion);
  *a.mutable_study() = study;
  a.set_case_name("reference");
  *a.mutable_node() = study.deployment().nodes(0);
  a.set_dt(0.001);
  a.add_storeys(0);
  a.add_actuators(0);
  return a;
}

transport::Message command(std::int64_t step, double drift) {
  runtime::Command c;
  c.set_time(static_cast<double>(step) * 0.001);
  c.add_drift(drift);
  c.add_drift_velocity(0.0);
  transport::Message m = runtime::pack(kRunId, 2, runtime::COMMAND, step, c);
  m.sent_ns = 1000 + step;  // the coordinator's stamp, which the answer must echo
  return m;
}

// The controller's end.
struct Controller {
  config::ControllerLink link;
  UdpLink udp;
  explicit Controller(const config::ControllerLink& l)
      : link(l), udp(l.peer_address(), l.peer_port(), l.local_address(), l.local_port()) {}
  std::optional<FrameValues> take(double seconds = 2.0) {
    Datagram d;
    const std::int64_t until = monotonic_ns() + static_cast<std::int64_t>(seconds * 1e9);
    while (!udp.try_receive(d))
      if (!udp.wait(until)) return std::nullopt;
    FrameValues v;
    EXPECT_EQ(decode(link.command(), d.bytes.data(), d.size, 1, v), FrameVerdict::kOk);
    return v;
  }
  void answer(std::int64_t counter, double drift, double force, std::int64_t status = 0,
              bool nan_force = false) {
    FrameValues v;
    v.counter = counter;
    v.status = status;
    v.measured_displacement = {drift};
    v.measured_force = {force};
    std::vector<std::uint8_t> bytes;
    EXPECT_TRUE(encode(link.feedback(), v, bytes));
    if (nan_force) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      std::memcpy(bytes.data() + 16, &nan, 8);
    }
    udp.send(bytes.data(), bytes.size());
  }
};

// What the answer thread sends within `seconds` (until `enough` of it, when given).
std::vector<transport::Message> answers(ControllerService& node, double seconds,
                                        std::size_t enough = 1) {
  std::vector<transport::Message> sent;
  const std::int64_t until = monotonic_ns() + static_cast<std::int64_t>(seconds * 1e9);
  while (monotonic_ns() < until && sent.size() < enough) {
    node.await_answers(monotonic_ns() + 1'000'000);
    node.take_answers([&](const transport::Message& m) { sent.push_back(m); });
  }
  return sent;
}

runtime::Ready assigned(ControllerService& node, const runtime::Assign& a) {
  const auto ready = node.handle(runtime::pack(kRunId, 2, runtime::ASSIGN, 0, a));
  runtime::Ready r;
  EXPECT_TRUE(runtime::unpack(ready.at(0), r));
  return r;
}

TEST(ControllerService, AnswersAsAnEmulatorAndHoldsTheRigOnARefusedFrame) {
  const runtime::Assign a = assign(47160, 47161, "");
  ControllerService node(2, kRunId);
  Controller controller(a.node().controller());
  ASSERT_EQ(assigned(node, a).error(), "");
  ASSERT_TRUE(node.asynchronous());

  EXPECT_TRUE(node.handle(command(1, 0.004)).empty());  // sent, nothing waits
  const auto c1 = controller.take();
  ASSERT_TRUE(c1);
  EXPECT_EQ(c1->target_displacement[0], 0.004);
  controller.answer(c1->counter, 0.004, 321.0);
  const auto replies = answers(node, 2.0);
  ASSERT_EQ(replies.size(), 1u);
  ASSERT_EQ(replies[0].kind, runtime::FEEDBACK);
  EXPECT_EQ(replies[0].step, 1);
  EXPECT_EQ(replies[0].echo_ns, 1001);
  runtime::Feedback f;
  ASSERT_TRUE(runtime::unpack(replies[0], f));
  EXPECT_EQ(f.realised(0), 0.004);
  EXPECT_EQ(f.force(0), 321.0);
  EXPECT_GT(f.controller_round_trip(), 0.0);

  // Step 2: the controller answers with a NaN force. The node holds and says why, and the rig
  // gets HOLD frames at the position it was last measured at.
  node.handle(command(2, 0.0041));
  controller.answer(controller.take()->counter, 0.0, 0.0, 0, true);
  const auto held = answers(node, 2.0);
  ASSERT_EQ(held.size(), 1u);
  EXPECT_EQ(held[0].kind, runtime::HOLD);
  runtime::Hold hold;
  ASSERT_TRUE(runtime::unpack(held[0], hold));
  EXPECT_NE(hold.reason().find("controller: frame from 127.0.0.1:47161 carries a value that is "
                               "not finite"),
            std::string::npos)
      << hold.reason();
  const auto hold_frame = controller.take();
  ASSERT_TRUE(hold_frame);
  EXPECT_EQ(hold_frame->status, kStatusHold);
  EXPECT_EQ(hold_frame->target_displacement[0], 0.004);  // measured, not the newest target
  EXPECT_TRUE(node.held());

  // Held: a later command is not acted on (no RUN frame goes to the controller).
  EXPECT_TRUE(node.handle(command(3, 0.0042)).empty());
  runtime::Heartbeat h;
  ASSERT_TRUE(runtime::unpack(node.heartbeat(), h));
  EXPECT_EQ(h.controller().frames_accepted(), 1u);
  EXPECT_EQ(h.controller().non_finite(), 1u);

  // STOP: no final heartbeat until the rig says held; then the STOP frame, then the heartbeat.
  EXPECT_TRUE(node.handle(runtime::pack(kRunId, 2, runtime::STOP, 3, runtime::Stop{})).empty());
  EXPECT_FALSE(node.at_rest());
  EXPECT_FALSE(node.final_heartbeat_due());
  // The answer thread repeats the HOLD frame every dt; the rig answers the next one held.
  bool answered_held = false;
  for (int i = 0; i < 200 && !node.at_rest(); ++i) {
    answers(node, 0.002);
    if (answered_held) continue;
    if (const auto frame = controller.take(0.002); frame && frame->status == kStatusHold) {
      controller.answer(frame->counter, 0.004, 0.0, kStatusHold);
      answered_held = true;
    }
  }
  ASSERT_TRUE(node.at_rest());
  std::optional<FrameValues> stop;
  while ((stop = controller.take(0.5)) && stop->status == kStatusHold) {}
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->status, kStatusStop);
  const auto final = node.final_heartbeat_due();
  ASSERT_TRUE(final);
  runtime::Heartbeat last;
  ASSERT_TRUE(runtime::unpack(*final, last));
  EXPECT_TRUE(last.final());
  EXPECT_GE(last.controller().held_after(), 0.0);
  EXPECT_FALSE(node.final_heartbeat_due());  // once
}

TEST(ControllerService, RealTimeHoldsOnLostFramesAStepBeforeTheAnswerWindowPasses) {
  const runtime::Assign a =
      assign(47162, 47163, "clock: REAL_TIME max_missed_answers: 3 max_overrun_fraction: -1", "");
  ControllerService node(2, kRunId);
  Controller controller(a.node().controller());  // bound, never answers
  ASSERT_EQ(assigned(node, a).error(), "");
  for (int step = 1; step <= 3; ++step) EXPECT_TRUE(node.handle(command(step, 0.0)).empty());
  const auto held = answers(node, 1.0);
  ASSERT_EQ(held.size(), 1u);
  EXPECT_EQ(held[0].kind, runtime::HOLD);
  runtime::Hold hold;
  ASSERT_TRUE(runtime::unpack(held[0], hold));
  // A window of 3 steps: the reply timeout 1 dt (half the window), so 2 lost frames in a row
  // (3 - 1) hold the node at 2 dt, a step before the coordinator's window passes.
  EXPECT_NE(hold.reason().find("within 1 ms (2 lost in a row)"), std::string::npos)
      << hold.reason();
  runtime::Heartbeat h;
  ASSERT_TRUE(runtime::unpack(node.heartbeat(), h));
  EXPECT_EQ(h.controller().lost(), 2u);
}

TEST(ControllerService, AReplyTimeoutBeyondTheAnswerWindowIsRefusedAtAssign) {
  ControllerService node(2, kRunId);
  const runtime::Ready r = assigned(
      node,
      assign(47164, 47165, "clock: REAL_TIME answer_window_ms: 5", "reply_timeout_ms: 1e300"));
  EXPECT_NE(
      r.error().find("reply_timeout_ms 1e+300 is longer than the answer window (5.000000 ms)"),
      std::string::npos)
      << r.error();
}

TEST(ControllerService, ABadLinkIsRefusedAtAssignNamingTheField) {
  runtime::Assign a = assign(47166, 47167, "");
  a.mutable_node()->mutable_controller()->mutable_command()->mutable_fields(0)->set_type(
      config::FrameField::F64);
  ControllerService node(2, kRunId);
  EXPECT_NE(assigned(node, a).error().find(
                "controller.command.fields[0] (counter): a COUNTER field is I32 or U32"),
            std::string::npos);
}

}  // namespace
}  // namespace rths::controller_node
