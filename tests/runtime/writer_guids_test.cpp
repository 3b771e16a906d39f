// WriterGuids (transport/writer_guids.h): what was added is found by its handle, nothing else
// is; a full table refuses more and keeps what it has; readers never see a half-written entry.
#include "transport/writer_guids.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace rths::transport {
namespace {

WriterGuid guid_for(std::uint64_t handle) {
  WriterGuid g{};
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = static_cast<std::uint8_t>(handle * 31 + i);
  return g;
}

TEST(WriterGuids, FindsWhatWasAddedByItsHandleOnly) {
  WriterGuids guids;
  EXPECT_EQ(guids.find(7), nullptr);
  ASSERT_TRUE(guids.add(7, guid_for(7)));
  ASSERT_TRUE(guids.add(9, guid_for(9)));
  ASSERT_NE(guids.find(7), nullptr);
  EXPECT_EQ(*guids.find(7), guid_for(7));
  EXPECT_EQ(*guids.find(9), guid_for(9));
  EXPECT_EQ(guids.find(8), nullptr);
  EXPECT_TRUE(guids.add(7, guid_for(1)));  // a handle added twice keeps its first GUID
  EXPECT_EQ(*guids.find(7), guid_for(7));
  EXPECT_EQ(guids.size(), 2u);
}

TEST(WriterGuids, AFullTableRefusesMoreAndKeepsWhatItHas) {
  WriterGuids guids;
  for (std::uint64_t h = 1; h <= WriterGuids::kCapacity; ++h)
    ASSERT_TRUE(guids.add(h, guid_for(h)));
  EXPECT_FALSE(guids.add(1000, guid_for(1000)));
  EXPECT_EQ(guids.find(1000), nullptr);
  EXPECT_EQ(guids.size(), WriterGuids::kCapacity);
  for (std::uint64_t h = 1; h <= WriterGuids::kCapacity; ++h)
    EXPECT_EQ(*guids.find(h), guid_for(h));
}

// Readers look up while a writer adds: every entry found is whole (its GUID the one added).
TEST(WriterGuids, ReadersFindWholeEntriesWhileOneIsAdded) {
  WriterGuids guids;
  std::atomic<bool> done{false};
  std::atomic<int> torn{0};
  std::vector<std::thread> readers;
  for (int t = 0; t < 3; ++t)
    readers.emplace_back([&] {
      while (!done)
        for (std::uint64_t h = 1; h <= WriterGuids::kCapacity; ++h)
          if (const WriterGuid* g = guids.find(h); g && *g != guid_for(h)) ++torn;
    });
  for (std::uint64_t h = 1; h <= WriterGuids::kCapacity; ++h) {
    guids.add(h, guid_for(h));
    std::this_thread::yield();
  }
  done = true;
  for (auto& r : readers) r.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(guids.size(), WriterGuids::kCapacity);
}

}  // namespace
}  // namespace rths::transport
