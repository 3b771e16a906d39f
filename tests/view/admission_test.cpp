// The admission rule on explicit state (no sockets, a clock of our own): room while there is
// room, then the connection idle longest is displaced, never the newest, and one address only
// ever displaces its own once it holds its share.
#include "view/admission.h"

#include <gtest/gtest.h>

namespace rths::view {
namespace {

using namespace std::chrono_literals;
using Clock = Admission::Clock;

constexpr std::uint32_t kHost = 0x7f000001;   // 127.0.0.1
constexpr std::uint32_t kOther = 0x0a000005;  // 10.0.0.5
const Clock::time_point kT0{};

TEST(Admission, DisplacesNothingWhileThereIsRoom) {
  Admission a({.max_waiting = 3, .max_per_address = 3});
  EXPECT_EQ(a.displaced_by(kHost), std::nullopt);
  a.add(10, kHost, kT0);
  a.add(11, kHost, kT0 + 1ms);
  EXPECT_EQ(a.displaced_by(kHost), std::nullopt);
  a.add(12, kHost, kT0 + 2ms);
  EXPECT_EQ(a.displaced_by(kHost), 10);
}

TEST(Admission, DisplacesTheOneThatHasSentNothingLongestNotTheNewest) {
  Admission a({.max_waiting = 3, .max_per_address = 3});
  a.add(10, kHost, kT0);        // a browser: its request begins at once
  a.add(11, kHost, kT0 + 1ms);  // idle since it came
  a.add(12, kHost, kT0 + 2ms);  // the newest, idle
  EXPECT_TRUE(a.saw_bytes(10, 16, kT0 + 1ms));
  EXPECT_EQ(a.displaced_by(kHost), 11);
  a.remove(11);
  a.add(13, kHost, kT0 + 3ms);
  EXPECT_EQ(a.displaced_by(kHost), 12);  // still the older of the two idle, not 13
}

TEST(Admission, AmongThoseThatSentPartOfARequestDisplacesTheOneSilentLongest) {
  Admission a({.max_waiting = 2, .max_per_address = 2});
  a.add(10, kHost, kT0);
  a.add(11, kHost, kT0 + 1ms);
  a.saw_bytes(10, 1, kT0 + 5ms);
  a.saw_bytes(11, 1, kT0 + 2ms);
  EXPECT_EQ(a.displaced_by(kHost), 11);
  EXPECT_TRUE(a.saw_bytes(11, 2, kT0 + 9ms));  // a byte more: active again
  EXPECT_EQ(a.displaced_by(kHost), 10);
  EXPECT_FALSE(a.saw_bytes(10, 1, kT0 + 10ms));  // no new byte: not active
  EXPECT_EQ(a.displaced_by(kHost), 10);
}

TEST(Admission, OneAddressAtItsShareDisplacesOnlyItsOwnAndLeavesRoomForOthers) {
  Admission a({.max_waiting = 4, .max_per_address = 3});
  a.add(20, kOther, kT0);  // another host's idle connection, the oldest of all
  a.add(10, kHost, kT0 + 1ms);
  a.add(11, kHost, kT0 + 2ms);
  EXPECT_EQ(a.displaced_by(kHost), std::nullopt);  // the table is not full
  a.add(12, kHost, kT0 + 3ms);
  EXPECT_EQ(a.from(kHost), 3u);
  EXPECT_EQ(a.displaced_by(kHost), 10);   // its own, although 20 is older
  EXPECT_EQ(a.displaced_by(kOther), 20);  // full: the idle-longest of all
  a.remove(20);
  EXPECT_EQ(a.displaced_by(kOther), std::nullopt);  // the slot kept for other addresses
}

TEST(Admission, TakesThoseWhoseDeadlinePassedInArrivalOrder) {
  Admission a({});
  a.add(10, kHost, kT0);
  a.add(11, kOther, kT0 + 1ms);
  a.add(12, kHost, kT0 + 5ms);
  a.saw_bytes(10, 3, kT0 + 4ms);  // bytes do not move a deadline: it counts from the arrival
  EXPECT_EQ(a.take_arrived_by(kT0 + 1ms), (std::vector<int>{10, 11}));
  EXPECT_EQ(a.fds(), std::vector<int>{12});
  EXPECT_FALSE(a.contains(10));
  EXPECT_FALSE(a.remove(10));
  EXPECT_FALSE(a.saw_bytes(10, 4, kT0 + 6ms));
  EXPECT_TRUE(a.remove(12));
  EXPECT_EQ(a.size(), 0u);
}

TEST(Admission, LimitsOfZeroAreTakenAsOne) {
  Admission a({.max_waiting = 0, .max_per_address = 0});
  EXPECT_EQ(a.displaced_by(kHost), std::nullopt);
  a.add(10, kHost, kT0);
  EXPECT_EQ(a.displaced_by(kOther), 10);
  EXPECT_EQ(a.displaced_by(kHost), 10);
}

}  // namespace
}  // namespace rths::view
