// parallel_for: every index runs exactly once, on the threads asked for, and the first
// exception of any item reaches the caller after every thread has joined.
#include "util/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace rths::util {
namespace {

TEST(ParallelFor, EveryIndexRunsExactlyOnce) {
  for (int threads : {1, 3, 8}) {
    constexpr std::size_t kCount = 1000;
    std::vector<std::atomic<int>> runs(kCount);
    parallel_for(kCount, threads, [&](std::size_t i) { runs[i].fetch_add(1); });
    for (std::size_t i = 0; i < kCount; ++i)
      ASSERT_EQ(runs[i].load(), 1) << "index " << i << ", " << threads << " threads";
  }
}

TEST(ParallelFor, RunsOnAtMostTheThreadsAskedForAndTheCallersIsOne) {
  std::mutex mutex;
  std::set<std::thread::id> seen;
  parallel_for(64, 3, [&](std::size_t) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    std::lock_guard<std::mutex> lock(mutex);
    seen.insert(std::this_thread::get_id());
  });
  EXPECT_LE(seen.size(), 3u);
  std::set<std::thread::id> single;
  parallel_for(5, 1, [&](std::size_t) { single.insert(std::this_thread::get_id()); });
  EXPECT_EQ(single, std::set<std::thread::id>{std::this_thread::get_id()});
}

TEST(ParallelFor, AnItemsExceptionReachesTheCallerAndStopsTheHandOut) {
  std::atomic<std::size_t> ran{0};
  try {
    parallel_for(20000, 4, [&](std::size_t i) {
      ran.fetch_add(1);
      if (i == 17) throw std::invalid_argument("item 17 failed");
      std::this_thread::sleep_for(std::chrono::microseconds(50));  // all of them: >= 0.25 s
    });
    FAIL() << "the exception was swallowed";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "item 17 failed");
  }
  EXPECT_LT(ran.load(), 20000u) << "items kept being handed out after the failure";
}

TEST(ParallelFor, NoItemsMeansNoCallsAndZeroThreadsMeansEveryCore) {
  bool called = false;
  parallel_for(0, 4, [&](std::size_t) { called = true; });
  EXPECT_FALSE(called);
  EXPECT_GE(resolve_threads(0), 1);
  EXPECT_EQ(resolve_threads(3), 3);
}

}  // namespace
}  // namespace rths::util
