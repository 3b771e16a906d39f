// The shared snapshot: however many callers loop on it, the build runs at most once per period
// (plus the first), and no sooner than kCostRatio times its last duration; every caller gets a
// whole copy.
#include "view/snapshot_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace rths::view {
namespace {

using namespace std::chrono_literals;

TEST(SnapshotCache, CallersLoopingOnItBuildAtMostOncePerPeriod) {
  std::atomic<int> built{0};
  SnapshotCache cache(
      [&] {
        std::this_thread::sleep_for(2ms);  // a build that takes a while, as a big feed's does
        return "copy " + std::to_string(++built);
      },
      100ms);
  const auto start = std::chrono::steady_clock::now();
  std::atomic<std::uint64_t> gets{0};
  std::vector<std::thread> callers;
  for (int t = 0; t < 6; ++t)
    callers.emplace_back([&] {
      while (std::chrono::steady_clock::now() - start < 600ms) {
        const auto copy = cache.get();
        ASSERT_TRUE(copy);
        ASSERT_EQ(copy->rfind("copy ", 0), 0u);
        ++gets;
      }
    });
  for (auto& c : callers) c.join();
  const double elapsed_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  // At most one build per started 100 ms, whatever the number of gets.
  EXPECT_LE(static_cast<double>(cache.builds()), elapsed_ms / 100.0 + 1.0);
  EXPECT_GE(cache.builds(), 2u);  // and it is rebuilt: the copy follows the feed
  EXPECT_EQ(cache.builds(), static_cast<std::uint64_t>(built.load()));
  EXPECT_EQ(cache.served(), gets.load());
  EXPECT_GT(gets.load(), 10 * cache.builds());
}

TEST(SnapshotCache, AFailedBuildIsRetriedByTheNextCaller) {
  int calls = 0;
  SnapshotCache cache(
      [&]() -> std::string {
        if (++calls == 1) throw std::runtime_error("feed gone");
        return "ok";
      },
      1000ms);
  EXPECT_THROW(cache.get(), std::runtime_error);
  EXPECT_EQ(*cache.get(), "ok");
  EXPECT_EQ(cache.builds(), 2u);
}

// A feed whose snapshot takes long to build (a long run's) is rebuilt no sooner than kCostRatio
// times its build's CPU time after it, however often callers ask: on clocks the test steps, each
// build "taking" what the build function moves them by.
TEST(SnapshotCache, ABuildThatTakesLongIsRepeatedOnlyAfterItsCostRatioTimesItsDuration) {
  auto now = std::chrono::steady_clock::time_point{};
  std::chrono::nanoseconds cpu{0};
  std::chrono::milliseconds build_takes = 10ms;
  int built = 0;
  SnapshotCache cache(
      [&] {
        now += build_takes;
        cpu += build_takes;
        return "copy " + std::to_string(++built);
      },
      200ms, [&] { return now; }, [&] { return cpu; });
  EXPECT_EQ(*cache.get(), "copy 1");  // a 10 ms build: the period rules (20 x 10 ms = 200 ms)
  now += 199ms;
  EXPECT_EQ(*cache.get(), "copy 1");
  now += 1ms;
  build_takes = 50ms;  // the feed has grown: 20 x 50 ms = 1 s until the next build
  EXPECT_EQ(*cache.get(), "copy 2");
  for (int i = 0; i < 99; ++i) {
    now += 10ms;
    EXPECT_EQ(*cache.get(), "copy 2") << "at " << i;
  }
  now += 10ms;  // 1 s after the second build ended
  EXPECT_EQ(*cache.get(), "copy 3");
  EXPECT_EQ(cache.builds(), 3u);
  EXPECT_EQ(cache.served(), 103u);
}

// A build preempted on a busy machine (500 ms on the wall, 10 ms of its thread's CPU) is not taken
// for a costly one: the next build comes at the 200 ms period, not 20 x 500 ms = 10 s later.
TEST(SnapshotCache, ABuildThatWaitedForACpuIsSpacedByItsCpuTimeNotItsWallTime) {
  auto now = std::chrono::steady_clock::time_point{};
  std::chrono::nanoseconds cpu{0};
  int built = 0;
  SnapshotCache cache(
      [&] {
        now += 500ms;
        cpu += 10ms;
        return "copy " + std::to_string(++built);
      },
      200ms, [&] { return now; }, [&] { return cpu; });
  EXPECT_EQ(*cache.get(), "copy 1");
  now += 199ms;
  EXPECT_EQ(*cache.get(), "copy 1");
  now += 1ms;
  EXPECT_EQ(*cache.get(), "copy 2");
  EXPECT_EQ(cache.builds(), 2u);
}

}  // namespace
}  // namespace rths::view
