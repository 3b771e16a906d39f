// AnswerWindow (the oldest answer a real-time step may apply, per node) and AnswerAgeTally (how
// old the applied answers were): the window grows with the lag the node's link injects, never
// with a lag nobody declared; the tally's quantiles are the applied ages'.
#include "coordinator/answer_age.h"

#include <gtest/gtest.h>

#include <google/protobuf/text_format.h>

namespace rths::coordinator {
namespace {

config::Deployment deployment(const std::string& text) {
  config::Deployment d;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &d)) << text;
  return d;
}

config::NodeSpec node(const std::string& text) {
  config::NodeSpec n;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &n)) << text;
  return n;
}

TEST(AnswerWindow, IsTheAnswerWindowWhenTheLinkInjectsNothing) {
  const AnswerWindow w(deployment("clock: REAL_TIME"), node("id: 2"), 0.001);
  EXPECT_EQ(w.steps(0.0), 3);  // max_missed_answers' default
  EXPECT_EQ(w.steps(100.0), 3);
  const AnswerWindow ms(deployment("answer_window_ms: 20"), node("id: 2"), 1.0 / 1024);
  EXPECT_EQ(ms.steps(0.0), 21);  // ceil(20 ms x 1024 Hz)
}

TEST(AnswerWindow, AddsTheRoundTripTheNodesLinkInjectsInWholeSteps) {
  // 4 ms down + 6 ms up, jitter 0.2 ms each (5 sigma: 1 ms each), a 3 ms spike: 15 ms.
  const config::NodeSpec spec = node(
      "id: 2 receive_lag { one_way_delay: 0.004 jitter: 0.0002 network { spike_delay: 0.003 "
      "spike_every: 100 spike_steps: 2 } } send_lag { one_way_delay: 0.006 jitter: 0.0002 }");
  const AnswerWindow w(deployment("max_missed_answers: 4"), spec, 0.001);
  EXPECT_EQ(w.steps(0.0), 4 + 15);
}

TEST(AnswerWindow, GrowsWithADriftingLinkAsTheRunGoesOn) {
  const AnswerWindow w(deployment(""), node("id: 2 receive_lag { network { drift_rate: 0.001 } }"),
                       0.001);
  EXPECT_EQ(w.steps(0.0), 3);
  EXPECT_EQ(w.steps(10.0), 3 + 10);  // 1 ms per s of simulated time
}

TEST(AnswerAgeTally, GivesTheMedianP99AndMaxOfTheAppliedAges) {
  AnswerAgeTally tally;
  for (int k = 0; k < 98; ++k) tally.step(1);
  tally.step(2);
  tally.step(7);
  const runtime::AnswerAge a = tally.summary(21, 0.001);
  EXPECT_EQ(a.steps_judged(), 100u);
  EXPECT_EQ(a.median_steps(), 1.0);
  EXPECT_EQ(a.p99_steps(), 2.0);
  EXPECT_EQ(a.max_steps(), 7.0);
  EXPECT_EQ(a.window_steps(), 21.0);
  EXPECT_EQ(a.dt(), 0.001);
}

TEST(AnswerAgeTally, KeepsTheMaxBeyondItsBinsAndSaysNothingBeforeAStep) {
  AnswerAgeTally tally;
  EXPECT_EQ(tally.summary(3, 0.001).steps_judged(), 0u);
  EXPECT_EQ(tally.summary(3, 0.001).max_steps(), 0.0);
  tally.step(100000);
  EXPECT_EQ(tally.summary(3, 0.001).max_steps(), 100000.0);
  EXPECT_EQ(tally.summary(3, 0.001).median_steps(), static_cast<double>(AnswerAgeTally::kBins - 1));
}

}  // namespace
}  // namespace rths::coordinator
