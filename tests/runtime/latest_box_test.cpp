// LatestBox: newest wins, nothing is taken twice, the taken value stays put, and a producer and a
// consumer thread never see a torn value.
#include "runtime/rt/latest_box.h"

#include <gtest/gtest.h>

#include <array>
#include <thread>

namespace rths::runtime {
namespace {

TEST(LatestBox, EmptyUntilSomethingIsPublished) {
  LatestBox<int> box;
  EXPECT_EQ(box.try_get(), nullptr);
  EXPECT_EQ(box.latest(), 0);
}

TEST(LatestBox, TheNewestValueWinsAndIsTakenOnce) {
  LatestBox<int> box;
  box.set(1);
  box.set(2);
  box.set(3);
  const int* got = box.try_get();
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(*got, 3);
  EXPECT_EQ(box.try_get(), nullptr) << "the same value must not be taken twice";
  EXPECT_EQ(box.latest(), 3);
}

TEST(LatestBox, ATakenValueStaysUnchangedWhileTheProducerGoesOn) {
  LatestBox<int> box;
  box.set(10);
  const int* taken = box.try_get();
  ASSERT_NE(taken, nullptr);
  for (int v = 11; v < 20; ++v) box.set(v);  // would overwrite a shared slot
  EXPECT_EQ(*taken, 10);
  const int* next = box.try_get();
  ASSERT_NE(next, nullptr);
  EXPECT_EQ(*next, 19);
}

TEST(LatestBox, FillingTheSlotInPlaceReusesItsStorage) {
  LatestBox<std::vector<double>> box;
  for (int round = 0; round < 6; ++round) {  // every one of the three slots grows once
    auto& slot = box.slot();
    slot.assign(64, static_cast<double>(round));
    box.publish();
    ASSERT_NE(box.try_get(), nullptr);
  }
  const double* storage = box.slot().data();
  box.slot().assign(64, 7.0);  // same size: no new storage
  EXPECT_EQ(box.slot().data(), storage);
}

// Each value is an array whose elements all equal its sequence number: a torn read (the consumer
// seeing a slot the producer is writing) shows elements that differ, and the sequence seen must
// never go back.
TEST(LatestBox, AProducerAndAConsumerThreadNeverSeeATornOrOlderValue) {
  using Value = std::array<std::uint64_t, 32>;
  LatestBox<Value> box;
  constexpr std::uint64_t kValues = 200'000;
  std::thread producer([&] {
    for (std::uint64_t n = 1; n <= kValues; ++n) {
      box.slot().fill(n);
      box.publish();
    }
  });
  std::uint64_t last = 0, taken = 0, torn = 0, backwards = 0;
  while (last < kValues) {
    const Value* v = box.try_get();
    if (!v) continue;
    ++taken;
    for (std::uint64_t x : *v) torn += x != (*v)[0] ? 1 : 0;
    if ((*v)[0] <= last) ++backwards;
    last = (*v)[0];
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_GT(taken, 0u);
  EXPECT_EQ(last, kValues);
}

}  // namespace
}  // namespace rths::runtime
