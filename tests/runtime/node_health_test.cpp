// One reading of a node's health from its footer entry: the controller link's line says
// "UDP frames rejected: none" only when every cause is 0, names each cause that is not, and the link's
// verdict fails a run fed by a wrong source or with lost frames; the answer age reads in steps
// and ms.
#include "runtime/record/node_health.h"

#include <gtest/gtest.h>

namespace rths::runtime {
namespace {

NodeRejects controller_node() {
  NodeRejects n;
  n.set_node_id(2);
  n.set_label("node 2 (controller)");
  ControllerReport& r = *n.mutable_controller();
  r.set_frames_sent(1000);
  r.set_frames_accepted(1000);
  r.set_round_trip_median(0.002);
  r.set_round_trip_p99(0.0025);
  r.set_round_trip_max(0.004);
  r.set_hold_frames(3);
  r.set_held_after(0.0021);
  return n;
}

TEST(NodeHealth, ACleanLinkReadsRejectedNoneAndHasNoVerdict) {
  const NodeRejects n = controller_node();
  const std::string text = controller_link_text(n);
  EXPECT_NE(text.find("node 2 (controller) controller link (UDP): 1000 frames sent, 1000 "
                      "accepted, 0 answered late, 0 lost (no answer within the reply timeout); "
                      "UDP frames rejected: none; UDP round trip ms: median 2.000, p99 2.500 "
                      "(applied answers), max 4.000 (every answer); 3 HOLD frames, held after "
                      "2.100 ms"),
            std::string::npos)
      << text;
  EXPECT_FALSE(link_verdict(n));
  EXPECT_EQ(node_health_json(n)["controller"]["rejected_total"], 0);
}

TEST(NodeHealth, EveryCauseIsNamedAndAWrongSourceOrALostFrameIsAVerdict) {
  NodeRejects n = controller_node();
  n.mutable_controller()->set_wrong_source(200);
  n.mutable_controller()->set_lost(19);
  const std::string text = controller_link_text(n);
  EXPECT_NE(text.find("19 lost (no answer within the reply timeout); UDP frames rejected: wrong "
                      "source 200;"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("rejected: none"), std::string::npos) << text;
  const auto verdict = link_verdict(n);
  ASSERT_TRUE(verdict);
  EXPECT_NE(verdict->find("19 frames lost, 0 answered late, 200 rejected (200 from a wrong "
                          "source"),
            std::string::npos)
      << *verdict;
  const auto j = node_health_json(n);
  EXPECT_EQ(j["controller"]["rejected"]["wrong source"], 200);
  EXPECT_EQ(j["controller"]["lost"], 19);
}

TEST(NodeHealth, LostAndLateFramesAreLocatedAndTheHoldIsATable) {
  NodeRejects n = controller_node();
  ControllerReport& r = *n.mutable_controller();
  r.set_lost(10);
  for (int i = 0; i < 10; ++i) {
    FrameMiss* m = r.add_lost_frames();
    m->set_counter(100 + i);
    m->set_step(99 + i);
  }
  r.set_late(1);
  FrameMiss* late = r.add_late_frames();
  late->set_counter(42);
  late->set_step(41);
  late->set_round_trip(0.0091);
  r.set_round_trip_max(0.0091);
  HoldEntry* sent = r.add_hold_log();
  sent->set_kind(HoldEntry::SENT_HOLD);
  sent->set_counter(111);
  sent->set_status(1);
  sent->add_position(0.0108);
  HoldEntry* answer = r.add_hold_log();
  answer->set_kind(HoldEntry::ANSWER);
  answer->set_time(0.002);
  answer->set_counter(9449);
  answer->set_status(1);
  answer->add_position(0.0);
  answer->add_force(12.0);
  answer->set_verdict("echoes frame 9449, never sent (newest 111)");
  r.set_hold_rejected(1);
  r.set_last_hold_reject(answer->verdict());
  r.set_icmp_errors(3);
  r.set_last_icmp_error("Connection refused (errno 111)");
  const std::string text = controller_link_text(n);
  EXPECT_NE(text.find("lost frames: 100 (step 99), 101 (step 100), 102 (step 101), 103 (step "
                      "102), 104 (step 103), 105 (step 104), 106 (step 105), 107 (step 106) and 2 "
                      "more"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("late frames: 42 (step 41)"), std::string::npos) << text;
  EXPECT_NE(text.find("max 9.100 (every answer)"), std::string::npos) << text;
  EXPECT_NE(text.find("1 answers while holding did not end the hold (newest: echoes frame 9449, "
                      "never sent"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("3 ICMP errors on the socket, never a fault by themselves (Connection "
                      "refused (errno 111))"),
            std::string::npos)
      << text;
  const auto j = node_health_json(n)["controller"];
  EXPECT_EQ(j["lost_frames"].size(), 10u);
  EXPECT_EQ(j["late_frames"][0]["step"], 41);
  ASSERT_EQ(j["hold"]["entries"].size(), 2u);
  EXPECT_EQ(j["hold"]["entries"][0]["kind"], "sent HOLD");
  EXPECT_DOUBLE_EQ(j["hold"]["entries"][0]["position_m"][0].get<double>(), 0.0108);
  EXPECT_EQ(j["hold"]["entries"][1]["verdict"], "echoes frame 9449, never sent (newest 111)");
}

TEST(NodeHealth, ANodeWithoutAControllerHasNoLinkLineNorVerdict) {
  NodeRejects n;
  n.set_label("node 1 (substructure)");
  EXPECT_EQ(controller_link_text(n), "");
  EXPECT_FALSE(link_verdict(n));
  EXPECT_TRUE(node_health_json(n)["controller"].is_null());
  EXPECT_TRUE(node_health_json(n)["answer_age"].is_null());
  EXPECT_EQ(answer_age_text(n), "");
}

TEST(NodeHealth, TheAnswerAgeReadsInStepsAndMs) {
  NodeRejects n = controller_node();
  AnswerAge& a = *n.mutable_answer_age();
  a.set_steps_judged(4096);
  a.set_median_steps(2);
  a.set_p99_steps(3);
  a.set_max_steps(5);
  a.set_window_steps(21);
  a.set_dt(0.001);
  EXPECT_EQ(answer_age_text(n),
            "node 2 (controller) answer age: median 2 steps (2.000 ms), p99 3 steps (3.000 ms), "
            "max 5 steps (5.000 ms); window 21 steps (21.000 ms)\n");
  EXPECT_DOUBLE_EQ(node_health_json(n)["answer_age"]["p99_ms"].get<double>(), 3.0);
}

}  // namespace
}  // namespace rths::runtime
