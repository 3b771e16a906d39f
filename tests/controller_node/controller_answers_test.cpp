// The controller as a node's answer source (controller_node/controller_answers.h), the test
// playing the controller over an in-process link (no ports): a stop holds the rig, sends one STOP
// once the controller answered held, and the exchange ends there: an answer that arrives after
// the STOP (the controller's late echo of an earlier HOLD frame) is neither judged nor logged,
// so the hold log ends in the STOP it sent.
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

TEST(ControllerAnswers, AnAnswerAfterTheStopIsNotReadAndTheHoldLogEndsInTheStop) {
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
  ASSERT_GT(report.hold_log_size(), 0);
  EXPECT_EQ(report.hold_log(report.hold_log_size() - 1).kind(), runtime::HoldEntry::SENT_STOP)
      << report.DebugString();
  EXPECT_EQ(controller.take(0.01).counter, 0) << "nothing leaves after the STOP";
}

}  // namespace
}  // namespace rths::controller_node
