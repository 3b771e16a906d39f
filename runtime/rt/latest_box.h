#pragma once
// LatestBox<T>: the newest value from one producer thread to one consumer thread, wait-free on
// both sides (a triple buffer). It is how the coordinator's real-time loop reads the newest
// feedback of a node without taking a lock its receive thread may hold.
//
//   producer   T& slot() -> fill it in place (its storage is reused: after the first values a
//              protobuf or vector in T stops allocating), then publish(). Or set(value).
//              Never fails and never waits: a value the consumer has not taken is replaced
//              (newest wins), which is what a real-time loop wants of a measurement.
//   consumer   try_get() -> the newest published value if one arrived since the last take,
//              else nullptr. The pointer (and latest()) stays valid and unchanged until the next
//              try_get(), so the loop can read from it with no copy.
// Three slots: the producer's, the consumer's, and the one in between that is swapped with an
// atomic exchange; a flag in the exchanged word says whether it holds an untaken value.
// Exactly one producer thread and one consumer thread at a time (a caller with several producer
// threads serialises them itself). T must be default constructible.

#include <array>
#include <atomic>
#include <cstdint>

namespace rths::runtime {

template <typename T>
class LatestBox {
 public:
  LatestBox() = default;
  LatestBox(const LatestBox&) = delete;
  LatestBox& operator=(const LatestBox&) = delete;

  // Producer: the slot to fill before publish(). Its previous contents are some older value.
  T& slot() { return slots_[write_]; }
  void publish() {
    const std::uint8_t old =
        middle_.exchange(static_cast<std::uint8_t>(write_ | kFresh), std::memory_order_acq_rel);
    write_ = old & kIndex;
  }
  void set(const T& value) {
    slot() = value;
    publish();
  }

  // Consumer: the newest value if one was published since the last take, else nullptr.
  const T* try_get() {
    if (!(middle_.load(std::memory_order_relaxed) & kFresh)) return nullptr;
    const std::uint8_t old = middle_.exchange(read_, std::memory_order_acq_rel);
    read_ = old & kIndex;
    return &slots_[read_];
  }
  // Consumer: the value taken last (a default T before the first take).
  const T& latest() const { return slots_[read_]; }

 private:
  static constexpr std::uint8_t kIndex = 0x3, kFresh = 0x4;
  std::array<T, 3> slots_{};
  std::uint8_t write_ = 0;               // producer's slot
  std::atomic<std::uint8_t> middle_{1};  // swapped slot, with kFresh when untaken
  std::uint8_t read_ = 2;                // consumer's slot
};

}  // namespace rths::runtime
