// The controller node's service as the coordinator sees it (messages in, messages out), with its
// controller a thread on real UDP sockets on 127.0.0.1: answers become FEEDBACK, a refused frame
// becomes a HOLD naming the cause and a HOLD status frame to the controller, the link report goes
// up in the heartbeat, STOP reaches the controller. UDP ports 47160-47169.
#include "controller_node/controller_service.h"

#include <gtest/gtest.h>

#include <cstring>
#include <future>
#include <limits>

#include "../runtime/test_support.h"
#include "link_text.h"
#include "runtime/node/schema.h"

namespace rths::controller_node {
namespace {

constexpr const char* kRunId = "controller-service-test";

runtime::Assign assign(int node_port, int peer_port, const std::string& deployment_extra) {
  const config::Study study = core::parse_study(
      test::paper_frame_study(
          0.5, "deployment { nodes { id: 2 kind: CONTROLLER controller { " +
                   test::controller_link_text(node_port, peer_port, "reply_timeout_ms: 100") +
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
  return runtime::pack(kRunId, 2, runtime::COMMAND, step, c);
}

// The controller's end: takes one frame; answers it with `frame(command)` unless that is empty.
struct Controller {
  config::ControllerLink link;
  UdpLink udp;
  explicit Controller(const config::ControllerLink& l)
      : link(l), udp(l.peer_address(), l.peer_port(), l.local_address(), l.local_port()) {}
  std::optional<FrameValues> take() {
    const auto d = udp.receive(monotonic_ns() + 2'000'000'000);
    if (!d) return std::nullopt;
    FrameValues v;
    EXPECT_EQ(decode(link.command(), d->bytes.data(), d->size, 1, v), FrameVerdict::kOk);
    return v;
  }
  std::vector<std::uint8_t> feedback(std::int64_t counter, double drift, double force) {
    FrameValues v;
    v.counter = counter;
    v.measured_displacement = {drift};
    v.measured_force = {force};
    std::vector<std::uint8_t> bytes;
    EXPECT_TRUE(encode(link.feedback(), v, bytes));
    return bytes;
  }
};

TEST(ControllerService, AnswersAsAnEmulatorAndHoldsTheRigOnARefusedFrame) {
  const runtime::Assign a = assign(47160, 47161, "");
  ControllerService node(2, kRunId);
  Controller controller(a.node().controller());
  const auto ready = node.handle(runtime::pack(kRunId, 2, runtime::ASSIGN, 0, a));
  runtime::Ready r;
  ASSERT_TRUE(runtime::unpack(ready.at(0), r));
  ASSERT_EQ(r.error(), "");
  ASSERT_EQ(r.storeys(), 1);

  auto good = std::async(std::launch::async, [&] {
    const auto c = controller.take();
    controller.udp.send(controller.feedback(c->counter, c->target_displacement[0], 321.0));
    return *c;
  });
  const auto replies = node.handle(command(1, 0.004));
  EXPECT_EQ(good.get().target_displacement[0], 0.004);
  ASSERT_EQ(replies.size(), 1u);
  ASSERT_EQ(replies[0].kind, runtime::FEEDBACK);
  runtime::Feedback f;
  ASSERT_TRUE(runtime::unpack(replies[0], f));
  EXPECT_EQ(f.realised(0), 0.004);
  EXPECT_EQ(f.force(0), 321.0);
  EXPECT_GT(f.controller_round_trip(), 0.0);

  // Step 2: the controller answers with a NaN force. The node holds and says why, and the rig
  // gets a HOLD status frame.
  auto bad = std::async(std::launch::async, [&] {
    const auto c = controller.take();
    auto frame = controller.feedback(c->counter, 0.0, 0.0);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::memcpy(frame.data() + 16, &nan, 8);
    controller.udp.send(frame);
    return controller.take();  // the HOLD status frame
  });
  const auto held = node.handle(command(2, 0.0041));
  const auto hold_frame = bad.get();
  ASSERT_EQ(held.size(), 1u);
  EXPECT_EQ(held[0].kind, runtime::HOLD);
  runtime::Hold hold;
  ASSERT_TRUE(runtime::unpack(held[0], hold));
  EXPECT_NE(hold.reason().find("controller: frame from 127.0.0.1:47161 carries a value that is "
                               "not finite"),
            std::string::npos)
      << hold.reason();
  ASSERT_TRUE(hold_frame);
  EXPECT_EQ(hold_frame->status, kStatusHold);
  EXPECT_EQ(hold_frame->target_displacement[0], 0.0041);  // the newest target: no jump
  EXPECT_TRUE(node.held());

  // Held: a later command is not acted on, and nothing goes to the controller.
  EXPECT_TRUE(node.handle(command(3, 0.0042)).empty());
  EXPECT_FALSE(controller.udp.receive(monotonic_ns() + 50'000'000));

  runtime::Heartbeat h;
  ASSERT_TRUE(runtime::unpack(node.heartbeat(), h));
  EXPECT_EQ(h.controller().frames_accepted(), 1u);
  EXPECT_EQ(h.controller().non_finite(), 1u);
  EXPECT_EQ(h.controller().frames_sent(), 3u);  // two commands and the HOLD

  const auto stopped = node.handle(runtime::pack(kRunId, 2, runtime::STOP, 3, runtime::Stop{}));
  ASSERT_EQ(stopped.size(), 1u);
  const auto stop_frame = controller.take();
  ASSERT_TRUE(stop_frame);
  EXPECT_EQ(stop_frame->status, kStatusStop);
}

TEST(ControllerService, RealTimeLeavesLostStepsUnansweredAndHoldsAfterTheWindow) {
  const runtime::Assign a =
      assign(47162, 47163, "clock: REAL_TIME max_missed_answers: 3 max_overrun_fraction: -1");
  ControllerService node(2, kRunId);
  Controller controller(a.node().controller());  // bound, never answers
  node.handle(runtime::pack(kRunId, 2, runtime::ASSIGN, 0, a));
  EXPECT_TRUE(node.handle(command(1, 0.0)).empty());
  EXPECT_TRUE(node.handle(command(2, 0.0)).empty());
  const auto third = node.handle(command(3, 0.0));
  ASSERT_EQ(third.size(), 1u);
  EXPECT_EQ(third[0].kind, runtime::HOLD);
  runtime::Heartbeat h;
  ASSERT_TRUE(runtime::unpack(node.heartbeat(), h));
  EXPECT_EQ(h.controller().lost(), 3u);
}

TEST(ControllerService, ABadLinkIsRefusedAtAssignNamingTheField) {
  runtime::Assign a = assign(47164, 47165, "");
  a.mutable_node()->mutable_controller()->mutable_command()->mutable_fields(0)->set_type(
      config::FrameField::F64);
  ControllerService node(2, kRunId);
  const auto ready = node.handle(runtime::pack(kRunId, 2, runtime::ASSIGN, 0, a));
  runtime::Ready r;
  ASSERT_TRUE(runtime::unpack(ready.at(0), r));
  EXPECT_NE(r.error().find("controller.command.fields[0] (counter): a COUNTER field is I32 or U32"),
            std::string::npos)
      << r.error();
}

}  // namespace
}  // namespace rths::controller_node
