// FeedbackIntake: what it accepts and rejects (as the coordinator's loop counts them), the answer
// and servo-sample rule, the lag it measures, the one wake-up per step, and a receive thread
// offering while the loop takes.
#include "coordinator/feedback_intake.h"

#include <gtest/gtest.h>

#include <thread>

#include "runtime/schema.h"

namespace rths::coordinator {
namespace {

transport::Message feedback(int node, std::int64_t step, double force, std::int64_t servo = 0,
                            const std::string& run = "run") {
  runtime::Feedback f;
  f.add_force(force);
  if (node == 2) f.add_realised(force * 1e-3);
  f.set_servo_sample(servo);
  f.set_command_received_ns(1'000'500);
  f.set_injected_lag(0.002);
  transport::Message m = runtime::pack(run, node, runtime::FEEDBACK, step, f);
  m.echo_ns = 1'000'000;
  m.sent_ns = 1'001'000;
  m.received_ns = 1'003'000;
  return m;
}

class Intake : public testing::Test {
 protected:
  // Node 1 a substructure (one storey), node 2 an emulator (one actuator).
  FeedbackIntake intake{"run", {{1, 1, false}, {2, 1, true}}};
};

TEST_F(Intake, NothingToTakeBeforeAnAnswer) {
  EXPECT_EQ(intake.take(1), nullptr);
  EXPECT_EQ(intake.latest(1).answers, 0u);
  EXPECT_EQ(intake.latest(1).feedback.force_size(), 0);
}

TEST_F(Intake, AnAnswerIsTakenWithItsForceCountAndLag) {
  intake.await_step(1);
  EXPECT_FALSE(intake.offer(feedback(1, 1, 5.0)));  // node 2 still owes step 1
  const ArrivedFeedback* got = intake.take(1);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->feedback.force(0), 5.0);
  EXPECT_EQ(got->answered_step, 1);
  EXPECT_EQ(got->answers, 1u);
  EXPECT_EQ(got->link.node_id(), 1);
  EXPECT_EQ(got->link.answered_step(), 1);
  EXPECT_NEAR(got->link.round_trip(), 3e-6, 1e-15);
  EXPECT_NEAR(got->link.one_way_down(), 0.5e-6, 1e-15);
  EXPECT_NEAR(got->link.one_way_up(), 2e-6, 1e-15);
  EXPECT_EQ(got->link.injected_lag(), 0.002);
  EXPECT_EQ(intake.take(1), nullptr);
}

TEST_F(Intake, TheLastAnswerToTheAwaitedStepAsksForTheWakeUp) {
  intake.await_step(3);
  EXPECT_FALSE(intake.offer(feedback(2, 2, 1.0)));  // an older step's answer completes nothing
  EXPECT_FALSE(intake.offer(feedback(1, 3, 1.0)));
  EXPECT_TRUE(intake.offer(feedback(2, 3, 1.0)));
  EXPECT_FALSE(intake.offer(feedback(2, 3, 2.0, 7))) << "a servo sample is not a new answer";
}

// A node the loop does not wait for (a real-time link slower than the wait) neither holds back
// the wake-up nor causes one; its answers are still taken.
TEST(IntakeNotAwaited, TheAwaitedNodesAloneCompleteAStep) {
  FeedbackIntake intake{"run", {{1, 1, false, true}, {2, 1, true, false}}};
  intake.await_step(4);
  EXPECT_FALSE(intake.offer(feedback(2, 4, 1.0)));
  EXPECT_TRUE(intake.offer(feedback(1, 4, 1.0)));
  intake.await_step(5);
  EXPECT_TRUE(intake.offer(feedback(1, 5, 1.0))) << "node 2 still owes step 5 and is not awaited";
  const ArrivedFeedback* got = intake.take(2);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->answered_step, 4);
}

TEST_F(Intake, RejectsAndCountsEachCause) {
  intake.await_step(5);
  intake.offer(feedback(1, 4, 1.0, 0, "other-run"));  // foreign run
  intake.offer(feedback(9, 4, 1.0));                  // unknown node
  intake.offer(feedback(1, 6, 1.0));                  // out of order: never commanded
  intake.offer(feedback(1, 4, 1.0));                  // accepted
  intake.offer(feedback(1, 4, 2.0));                  // duplicate (no newer servo sample)
  intake.offer(feedback(1, 3, 1.0));                  // stale
  transport::Message garbage = feedback(1, 5, 1.0);
  garbage.payload = "\xff\xff\xff";
  intake.offer(garbage);
  runtime::Feedback two_forces;
  two_forces.add_force(1.0);
  two_forces.add_force(2.0);
  intake.offer(runtime::pack("run", 1, runtime::FEEDBACK, 5, two_forces));  // wrong size
  runtime::Feedback no_realised;
  no_realised.add_force(1.0);
  intake.offer(runtime::pack("run", 2, runtime::FEEDBACK, 5, no_realised));  // emulator w/o realised
  const runtime::RejectCounters r = intake.rejected();
  EXPECT_EQ(r.foreign_run, 1u);
  EXPECT_EQ(r.unknown_node, 1u);
  EXPECT_EQ(r.out_of_order, 1u);
  EXPECT_EQ(r.duplicate, 1u);
  EXPECT_EQ(r.stale, 1u);
  EXPECT_EQ(r.garbage, 3u);
  const ArrivedFeedback* got = intake.take(1);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->feedback.force(0), 1.0) << "no rejected message may reach the box";
  EXPECT_EQ(got->answers, 1u);
}

TEST_F(Intake, ANewerServoSampleReplacesTheMeasurementButKeepsTheAnswersLag) {
  intake.await_step(2);
  intake.offer(feedback(2, 2, 1.0, 10));
  transport::Message later = feedback(2, 2, 3.0, 12);
  later.received_ns = 1'090'000;  // would be a longer round trip if it counted as the answer
  intake.offer(later);
  intake.offer(feedback(2, 2, 9.0, 11));  // older sample: duplicate
  const ArrivedFeedback* got = intake.take(2);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->feedback.force(0), 3.0);
  EXPECT_EQ(got->answers, 1u);
  EXPECT_NEAR(got->link.round_trip(), 3e-6, 1e-15);
  EXPECT_EQ(intake.rejected().duplicate, 1u);
}

TEST_F(Intake, NewestWinsAndCarriesEveryAnswerCount) {
  for (int step = 1; step <= 5; ++step) {
    intake.await_step(step);
    intake.offer(feedback(1, step, step * 10.0));
  }
  const ArrivedFeedback* got = intake.take(1);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->feedback.force(0), 50.0);
  EXPECT_EQ(got->answered_step, 5);
  EXPECT_EQ(got->answers, 5u) << "answers the loop did not take one by one still count";
}

// A receive thread offers answers to ever newer steps while the loop takes: every taken value is
// whole (force = 10 x its step) and never older than the one before.
TEST_F(Intake, AReceiveThreadAndTheLoopNeverSeeATornOrOlderAnswer) {
  constexpr int kSteps = 20'000;
  intake.await_step(kSteps);
  std::thread receiver([&] {
    for (int step = 1; step <= kSteps; ++step) intake.offer(feedback(1, step, step * 10.0));
  });
  std::int64_t last = 0;
  int torn = 0, backwards = 0;
  while (last < kSteps) {
    const ArrivedFeedback* got = intake.take(1);
    if (!got) continue;
    torn += got->feedback.force(0) != 10.0 * static_cast<double>(got->answered_step) ? 1 : 0;
    torn += got->answers != static_cast<std::uint64_t>(got->answered_step) ? 1 : 0;
    backwards += got->answered_step <= last ? 1 : 0;
    last = got->answered_step;
  }
  receiver.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(backwards, 0);
  EXPECT_EQ(intake.rejected().total(), 0u);
}

}  // namespace
}  // namespace rths::coordinator
