// One reading of a node's health from its footer entry: the controller link's line says
// "rejected: none" only when every cause is 0, names each cause that is not, and the link's
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
  EXPECT_NE(text.find("node 2 (controller) controller link: 1000 frames sent, 1000 accepted, 0 "
                      "late, 0 lost; rejected: none; UDP round trip ms: median 2.000, p99 2.500, "
                      "max 4.000; 3 HOLD frames, held after 2.100 ms"),
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
  EXPECT_NE(text.find("19 lost; rejected: wrong source 200;"), std::string::npos) << text;
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
