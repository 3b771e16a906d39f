// The control room's rules: each role's token names its role; the director HOLDs any lab and
// STOPs; an operator HOLDs only their own lab and never STOPs; a viewer presses nothing; every
// press of a known role is queued for the loop, allowed or refused, and an unknown token queues
// nothing.
#include "view/control_room.h"

#include <gtest/gtest.h>

namespace rths::view {
namespace {

ControlDesk desk() {
  return ControlDesk(Crew::make({"lab_b", "lab_c"}), {{"lab_b", {2, 3}}, {"lab_c", {4}}});
}

TEST(Crew, EachTokenNamesItsRoleAndNoOther) {
  const Crew crew = Crew::make({"lab_b", "lab_c"});
  EXPECT_EQ(crew.identify(crew.director)->name(), "the director");
  EXPECT_EQ(crew.identify(crew.viewer)->name(), "a viewer");
  EXPECT_EQ(crew.identify(crew.operators.at("lab_c"))->name(), "the operator of lab_c");
  EXPECT_FALSE(crew.identify(""));
  EXPECT_FALSE(crew.identify(crew.director.substr(1)));
  EXPECT_FALSE(crew.identify(crew.director + "0"));
  EXPECT_NE(crew.director, crew.viewer);
  EXPECT_NE(crew.operators.at("lab_b"), crew.operators.at("lab_c"));
  const Crew again = Crew::from_json(crew.to_json());
  EXPECT_EQ(again.identify(crew.operators.at("lab_b"))->lab, "lab_b");
}

TEST(Crew, FromJsonRefusesAMissingOrShortToken) {
  const auto message = [](const nlohmann::json& j) {
    try {
      Crew::from_json(j);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string t(32, 'a');
  EXPECT_NE(message({{"viewer", t}}).find("the director's token is missing"), std::string::npos);
  EXPECT_NE(message({{"director", t}, {"viewer", t}, {"operators", {{"lab_b", "short"}}}})
                .find("the operator of lab_b's token has under 16 characters"),
            std::string::npos);
}

TEST(ControlDesk, AnOperatorHoldsOnlyTheirOwnLabAndNeverStops) {
  ControlDesk d = desk();
  const std::string token = d.crew().operators.at("lab_b");
  const auto own = d.press(token, "hold", "lab_b", 41);
  ASSERT_TRUE(own);
  EXPECT_EQ(own->seen_step, 41);  // the newest step the view had seen, for the loop's event
  EXPECT_TRUE(own->allowed);
  EXPECT_EQ(own->hold_nodes, (std::vector<int>{2, 3}));
  EXPECT_FALSE(own->stop);
  EXPECT_EQ(own->text(),
            "the operator of lab_b pressed HOLD of lab_b on the view: HOLD sent to nodes 2, 3; "
            "the run holds until the director stops it");
  const auto other = d.press(token, "hold", "lab_c");
  EXPECT_FALSE(other->allowed);
  EXPECT_TRUE(other->hold_nodes.empty());
  EXPECT_EQ(other->why, "the operator of lab_b may HOLD only lab_b's actuators");
  const auto every = d.press(token, "hold", "");
  EXPECT_FALSE(every->allowed);
  const auto stop = d.press(token, "stop", "");
  EXPECT_FALSE(stop->allowed);
  EXPECT_FALSE(stop->stop);
  EXPECT_EQ(stop->text(),
            "the operator of lab_b pressed STOP on the view: refused (403), only the director may "
            "stop the test");
  EXPECT_TRUE(d.pending());
  const auto queued = d.take();
  ASSERT_EQ(queued.size(), 4u);  // the refused ones too: the record names them
  EXPECT_EQ(queued[1].what, "HOLD of lab_c");
  EXPECT_FALSE(d.pending());
  EXPECT_TRUE(d.take().empty());
}

TEST(ControlDesk, TheDirectorHoldsAnyLabOrAllAndStops) {
  ControlDesk d = desk();
  const std::string token = d.crew().director;
  EXPECT_EQ(d.press(token, "hold", "lab_c")->hold_nodes, std::vector<int>{4});
  EXPECT_EQ(d.press(token, "hold", "")->hold_nodes, (std::vector<int>{2, 3, 4}));
  const auto stop = d.press(token, "stop", "");
  EXPECT_TRUE(stop->allowed);
  EXPECT_TRUE(stop->stop);
  const auto unknown = d.press(token, "hold", "lab_z");
  EXPECT_FALSE(unknown->allowed);
  EXPECT_EQ(unknown->why, "'lab_z' is not a lab with actuators in this run");
  EXPECT_FALSE(d.press(token, "release", "lab_b")->allowed);  // nothing releases a HOLD
}

TEST(ControlDesk, AViewerPressesNothingAndAnUnknownTokenQueuesNothing) {
  ControlDesk d = desk();
  EXPECT_FALSE(d.press(d.crew().viewer, "stop", "")->allowed);
  EXPECT_EQ(d.press(d.crew().viewer, "hold", "lab_b")->why, "a viewer may not HOLD");
  EXPECT_EQ(d.take().size(), 2u);
  EXPECT_FALSE(d.press("0123456789abcdef0123456789abcdef", "stop", ""));
  EXPECT_FALSE(d.press("", "hold", "lab_b"));
  EXPECT_FALSE(d.pending());
}

TEST(ControlDesk, RefusesAnOperatorOfASiteWithoutActuators) {
  EXPECT_THROW(ControlDesk(Crew::make({"site_a"}), {{"lab_b", {2}}}), std::invalid_argument);
}

}  // namespace
}  // namespace rths::view
