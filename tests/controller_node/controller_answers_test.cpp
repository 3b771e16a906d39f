// The controller as a node's answer source (controller_node/controller_answers.h), the test
// playing the controller over an in-process link (no ports): a stop holds the rig and sends one
// STOP once the controller answered held; after it the node sends nothing, and an answer that
// still arrives (the controller's late echo of an earlier HOLD frame) is read and logged after
// the STOP, so the record shows a controller that went on answering.
#include <gtest/gtest.h>

#include <memory>

#include "controller_node/controller_answers.h"
#include "in_process_link.h"
#include "link_text.h"
#include "test_controller.h"

namespace rths::controller_node {
namespace {

ExchangeSettings settings() {
  ExchangeSettings s;
  s.actuators = 1;
  s.dt = 0.001;
  s.reply_timeout = 0.5;
  s.max_drift = 0.2;
  s.max_force = 1e6;
  s.hold_time = 0.3;
  return s;
}

// The next frame the node sends, stepping its answer source meanwhile.
FrameValues next_frame(ControllerAnswers& answers, test::TestController& controller) {
  runtime::Feedback feedback;
  FrameValues v;
  const std::int64_t until = monotonic_ns() + 200'000'000;
  while (v.counter == 0 && monotonic_ns() < until) {
    answers.next(feedback);
    v = controller.take(0.0005);
  }
  return v;
}

TEST(ControllerAnswers, AnAnswerAfterTheStopIsLoggedAfterItAndNothingIsSent) {
  const config::ControllerLink link = test::controller_link(47446, 47447);
  test::InProcessLinkPair pair(test::real_clock());
  ControllerAnswers answers(std::make_unique<ControllerExchange>(link, settings(), pair.node_end()),
                            "node 9 (controller)");
  test::TestController controller(link, pair.controller(), test::real_clock());
  answers.stop();
  const FrameValues first_hold = next_frame(answers, controller);
  ASSERT_EQ(first_hold.status, kStatusHold);
  const FrameValues second_hold = next_frame(answers, controller);
  ASSERT_EQ(second_hold.status, kStatusHold);
  controller.answer(second_hold.counter, 0.0, 0.0, kStatusHold);
  const FrameValues stop = next_frame(answers, controller);
  ASSERT_EQ(stop.status, kStatusStop);
  ASSERT_TRUE(answers.rested());
  // The controller's late answer to the first HOLD frame, after the STOP left.
  controller.answer(first_hold.counter, 0.0, 0.0, kStatusHold);
  runtime::Feedback feedback;
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(answers.next(feedback).kind, runtime::AnswerSource::Next::Kind::kNone);
    answers.wait(monotonic_ns() + 1'000'000);
  }
  const runtime::ControllerReport& report = answers.exchange().report();
  int stop_entry = -1;
  for (int i = 0; i < report.hold_log_size(); ++i)
    if (report.hold_log(i).kind() == runtime::HoldEntry::SENT_STOP) stop_entry = i;
  ASSERT_GE(stop_entry, 0) << report.DebugString();
  ASSERT_EQ(report.hold_log_size(), stop_entry + 2) << report.DebugString();
  EXPECT_EQ(report.hold_log(stop_entry + 1).kind(), runtime::HoldEntry::ANSWER);
  EXPECT_EQ(report.hold_log(stop_entry + 1).counter(), first_hold.counter);
  EXPECT_EQ(controller.take(0.01).counter, 0) << "nothing leaves after the STOP";
}

}  // namespace
}  // namespace rths::controller_node
