#include "coordinator/flood_blame.h"

#include <gtest/gtest.h>

#include <string>

namespace rths::coordinator {
namespace {

TEST(FloodBlame, NothingDroppedBlamesNoOne) {
  EXPECT_FALSE(
      unauthenticated_flood({{"coordinator", 0}, {"node 2 (actuator emulator)", 0}}, 3.0, "")
          .has_value());
}

TEST(FloodBlame, NamesEachReceiverThatDroppedTheTotalAndItsRate) {
  const auto text = unauthenticated_flood(
      {{"coordinator", 3000}, {"node 1 (substructure)", 0}, {"node 2 (actuator emulator)", 1500}},
      0.2, "kind 4 as node 1 on node 1's topic, writer 9");
  ASSERT_TRUE(text.has_value());
  EXPECT_EQ(*text,
            "; meanwhile 4500 unauthenticated messages (22500 a second) were dropped unread "
            "(coordinator 3000, node 2 (actuator emulator) 1500; newest: kind 4 as node 1 on node "
            "1's topic, writer 9): a flood on the run's DDS domain took receive time from the "
            "loop (a flood from 8333 a second: 1 % of the run's time at 1.2 us a message)");
}

// The attack's five forged messages, one a second: named as what they are, never a flood.
TEST(FloodBlame, AHandfulOfForgedMessagesIsNeverCalledAFlood) {
  const auto text = unauthenticated_flood({{"coordinator", 5}}, 5.0, "kind 2 as node 2");
  ASSERT_TRUE(text.has_value());
  EXPECT_EQ(text->find("a flood on"), std::string::npos) << *text;
  EXPECT_EQ(*text,
            "; meanwhile 5 unauthenticated messages (1 a second) were dropped unread (coordinator "
            "5; newest: kind 2 as node 2): too few to take the loop's time (about 0.006 ms of "
            "receive work in the run's 5 s, under 1 %; a flood from 8333 a second), not the cause");
}

// The threshold, from both sides: kFloodShare of the run's time at kDropSeconds a message.
TEST(FloodBlame, AFloodIsNamedFromTheRateWhoseReceiveWorkIsOnePercentOfTheRun) {
  const auto at = [](std::uint64_t count) {
    return unauthenticated_flood({{"coordinator", count}}, 10.0, "")->find("a flood on the");
  };
  EXPECT_NE(at(83334), std::string::npos);  // 8333.4 a second
  EXPECT_EQ(at(83332), std::string::npos);  // 8333.2 a second
  EXPECT_NE(at(2'000'000), std::string::npos);
}

}  // namespace
}  // namespace rths::coordinator
