#include "coordinator/flood_blame.h"

#include <gtest/gtest.h>

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
      2.0, "kind 4 as node 1 on node 1's topic, writer 9");
  ASSERT_TRUE(text.has_value());
  EXPECT_EQ(*text,
            "; meanwhile 4500 unauthenticated messages (2250 a second) were dropped unread "
            "(coordinator 3000, node 2 (actuator emulator) 1500; newest: kind 4 as node 1 on node "
            "1's topic, writer 9): a flood on the run's DDS domain took receive time from the "
            "loop");
}

}  // namespace
}  // namespace rths::coordinator
