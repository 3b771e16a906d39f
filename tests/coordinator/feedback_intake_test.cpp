// FeedbackIntake: what it accepts and rejects (as the coordinator's loop counts them), the answer
// and servo-sample rule, the lag it measures, the one wake-up per step, the integrity faults, and
// a receive thread offering while the loop takes.
#include "coordinator/feedback_intake.h"

#include <gtest/gtest.h>

#include <limits>
#include <thread>

#include "runtime/node/schema.h"

namespace rths::coordinator {
namespace {

constexpr std::int64_t kEcho = 1'000'000;  // every test command's sent_ns

transport::Message feedback(int node, std::int64_t step, double force, std::int64_t servo = 0,
                            const std::string& run = "run") {
  runtime::Feedback f;
  f.add_force(force);
  if (node == 2) f.add_realised(force * 1e-3);
  f.set_servo_sample(servo);
  f.set_command_received_ns(1'000'500);
  f.set_injected_lag(0.002);
  transport::Message m = runtime::pack(run, node, runtime::FEEDBACK, step, f);
  m.echo_ns = kEcho;
  m.sent_ns = 1'001'000;
  m.received_ns = 1'003'000;
  return m;
}

// The loop's side of a step: awaits it, then sends each node its command stamped kEcho.
void command(FeedbackIntake& intake, std::int64_t step, const std::vector<int>& nodes = {1, 2}) {
  intake.await_step(step);
  for (const int node : nodes) intake.command_sent(node, kEcho);
}

class Intake : public testing::Test {
 protected:
  void command(std::int64_t step) { coordinator::command(intake, step); }
  // Node 1 a substructure (one storey), node 2 an emulator (one actuator); |realised| <= 0.5 m.
  FeedbackIntake intake{"run", {{1, 1, false}, {2, 1, true}}, 0.5};
};

TEST_F(Intake, NothingToTakeBeforeAnAnswer) {
  EXPECT_EQ(intake.take(1), nullptr);
  EXPECT_EQ(intake.latest(1).answers, 0u);
  EXPECT_EQ(intake.latest(1).feedback.force_size(), 0);
}

TEST_F(Intake, AnAnswerIsTakenWithItsForceCountAndLag) {
  command(1);
  EXPECT_FALSE(intake.offer(feedback(1, 1, 5.0)));  // node 2 still owes step 1
  const ArrivedFeedback* got = intake.take(1);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->feedback.force(0), 5.0);
  EXPECT_EQ(got->answered_step, 1);
  EXPECT_EQ(got->answers, 1u);
  EXPECT_EQ(got->link.node_id(), 1);
  EXPECT_EQ(got->link.answered_step(), 1);
  EXPECT_EQ(got->link.answers(), 1u);
  EXPECT_NEAR(got->link.round_trip(), 3e-6, 1e-15);
  EXPECT_NEAR(got->link.one_way_down(), 0.5e-6, 1e-15);
  EXPECT_NEAR(got->link.one_way_up(), 2e-6, 1e-15);
  EXPECT_EQ(got->link.injected_lag(), 0.002);
  EXPECT_EQ(intake.take(1), nullptr);
}

TEST_F(Intake, TheLastAnswerToTheAwaitedStepAsksForTheWakeUp) {
  command(3);
  EXPECT_FALSE(intake.offer(feedback(2, 2, 1.0)));  // an older step's answer completes nothing
  EXPECT_FALSE(intake.offer(feedback(1, 3, 1.0)));
  EXPECT_TRUE(intake.offer(feedback(2, 3, 1.0)));
  EXPECT_FALSE(intake.offer(feedback(2, 3, 2.0, 7))) << "a servo sample is not a new answer";
}

// A node the loop does not wait for (a real-time link slower than the wait) neither holds back
// the wake-up nor causes one; its answers are still taken.
TEST(IntakeNotAwaited, TheAwaitedNodesAloneCompleteAStep) {
  FeedbackIntake intake{"run", {{1, 1, false, true}, {2, 1, true, false}}};
  command(intake, 4);
  EXPECT_FALSE(intake.offer(feedback(2, 4, 1.0)));
  EXPECT_TRUE(intake.offer(feedback(1, 4, 1.0)));
  command(intake, 5);
  EXPECT_TRUE(intake.offer(feedback(1, 5, 1.0))) << "node 2 still owes step 5 and is not awaited";
  const ArrivedFeedback* got = intake.take(2);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->answered_step, 4);
  // Node 1's answer to step 4 was superseded by its answer to step 5 before the loop took one:
  // the link's count says both arrived.
  got = intake.take(1);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->link.answered_step(), 5);
  EXPECT_EQ(got->link.answers(), 2u);
}

// The loop stops (or starts again) waiting for a node in the middle of a run: the wake-up
// follows at once.
TEST_F(Intake, ANodeTheLoopStopsWaitingForNoLongerHoldsBackTheWakeUp) {
  command(6);
  intake.set_awaited(2, false);
  EXPECT_TRUE(intake.offer(feedback(1, 6, 1.0)));
  EXPECT_FALSE(intake.offer(feedback(2, 6, 1.0)));
  intake.set_awaited(2, true);
  command(7);
  EXPECT_FALSE(intake.offer(feedback(1, 7, 1.0)));
  EXPECT_TRUE(intake.offer(feedback(2, 7, 1.0)));
}

TEST_F(Intake, RejectsAndCountsEachCause) {
  command(5);
  intake.offer(feedback(1, 4, 1.0, 0, "other-run"));  // foreign run
  intake.offer(feedback(9, 4, 1.0));                  // unknown node
  intake.offer(feedback(1, 6, 1.0));                  // out of order: never commanded
  intake.offer(feedback(1, 4, 1.0));                  // accepted
  intake.offer(feedback(1, 4, 1.0));                  // duplicate: the same answer again
  intake.offer(feedback(1, 3, 1.0));                  // stale
  transport::Message garbage = feedback(1, 5, 1.0);
  garbage.payload = "\xff\xff\xff";
  intake.offer(garbage);
  runtime::Feedback two_forces;
  two_forces.add_force(1.0);
  two_forces.add_force(2.0);
  transport::Message wrong_size = runtime::pack("run", 1, runtime::FEEDBACK, 5, two_forces);
  wrong_size.echo_ns = kEcho;
  intake.offer(wrong_size);
  runtime::Feedback no_realised;
  no_realised.add_force(1.0);
  transport::Message emulator_without_realised =
      runtime::pack("run", 2, runtime::FEEDBACK, 5, no_realised);
  emulator_without_realised.echo_ns = kEcho;
  intake.offer(emulator_without_realised);
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
  EXPECT_EQ(intake.fault(), nullptr);
}

TEST_F(Intake, NothingForAStepIsAcceptedBeforeItsCommandLeft) {
  intake.await_step(1);  // the step is commanded, its commands not yet sent
  EXPECT_FALSE(intake.offer(feedback(1, 1, 1.0)));
  intake.command_sent(1, kEcho + 1);
  EXPECT_FALSE(intake.offer(feedback(1, 1, 1.0))) << "echoes another command";
  EXPECT_EQ(intake.rejected().out_of_order, 2u);
  EXPECT_EQ(intake.take(1), nullptr);
  intake.command_sent(1, kEcho);
  intake.offer(feedback(1, 1, 1.0));
  EXPECT_NE(intake.take(1), nullptr);
}

TEST_F(Intake, ValuesThatAreNotFiniteOrBeyondTheLimitsAreRejected) {
  command(1);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  intake.offer(feedback(1, 1, nan));
  intake.offer(feedback(1, 1, std::numeric_limits<double>::infinity()));
  intake.offer(feedback(2, 1, 1e3));  // realised 1 m, beyond 0.5 m
  transport::Message negative_lag = feedback(1, 1, 1.0);
  runtime::Feedback f;
  ASSERT_TRUE(runtime::unpack(negative_lag, f));
  f.set_injected_lag(-1.0);
  f.SerializeToString(&negative_lag.payload);
  intake.offer(negative_lag);
  EXPECT_EQ(intake.rejected().out_of_range, 4u);
  EXPECT_EQ(intake.take(1), nullptr);
  EXPECT_EQ(intake.take(2), nullptr);
}

TEST_F(Intake, ANodesIdOnAnotherNodesTopicIsNotEntitled) {
  command(1);
  transport::Message claim = feedback(1, 1, 1.0);
  claim.topic_node = 2;
  EXPECT_FALSE(intake.offer(claim));
  EXPECT_EQ(intake.rejected().not_entitled, 1u);
  EXPECT_EQ(intake.take(1), nullptr);
  EXPECT_EQ(intake.fault(), nullptr);
}

TEST_F(Intake, TwoDifferentAnswersToOneStepAreAnIntegrityFaultNamingBothArrivals) {
  command(1);
  intake.offer(feedback(1, 1, 1.0));
  EXPECT_EQ(intake.fault(), nullptr);
  transport::Message second = feedback(1, 1, 12345.0);
  second.received_ns = 1'007'000;
  EXPECT_TRUE(intake.offer(second)) << "a fault wakes the loop";
  const IntegrityFault* fault = intake.fault();
  ASSERT_NE(fault, nullptr);
  EXPECT_EQ(fault->node_id, 1);
  EXPECT_NE(fault->what.find("integrity fault: two different answers to step 1 from node 1"),
            std::string::npos)
      << fault->what;
  EXPECT_NE(fault->what.find("1003000"), std::string::npos) << fault->what;
  EXPECT_NE(fault->what.find("1007000"), std::string::npos) << fault->what;
  const ArrivedFeedback* got = intake.take(1);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->feedback.force(0), 1.0) << "the second answer is never applied";
}

TEST_F(Intake, AnAnswerFromAnotherWriterThanTheNodesIsAnIntegrityFault) {
  intake.pin(1, 7);
  command(1);
  transport::Message own = feedback(1, 1, 1.0);
  own.writer = 7;
  intake.offer(own);
  transport::Message forged = feedback(1, 2, 12345.0);  // even a step not yet commanded
  forged.writer = 9;
  EXPECT_TRUE(intake.offer(forged));
  const IntegrityFault* fault = intake.fault();
  ASSERT_NE(fault, nullptr);
  EXPECT_EQ(fault->node_id, 1);
  EXPECT_NE(fault->what.find("another participant answers as node 1"), std::string::npos)
      << fault->what;
  EXPECT_NE(fault->what.find("writer 9"), std::string::npos) << fault->what;
  EXPECT_NE(fault->what.find("writer 7"), std::string::npos) << fault->what;
  EXPECT_EQ(intake.rejected().not_entitled, 1u);
}

TEST_F(Intake, ANewerServoSampleReplacesTheMeasurementButKeepsTheAnswersLag) {
  command(2);
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
    command(step);
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
  command(kSteps);
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
