#pragma once
// WriterGuids: the DDS GUIDs of the remote writers a receiver has authenticated, by publication
// handle (the sample info's), so finding a sample's writer GUID for its MAC
// (transport/message_mac.h) costs a scan of a few entries: no allocation, no lock, no DDS call.
//
// Inputs: add(handle, guid), any thread (serialised by a mutex); find(handle), any thread, no lock.
// Output: the GUID added for that handle, or null.
// Append only, at most kCapacity entries: an entry never changes once published (the count is
// released after it is written), which is what lets find() read without a lock. The caller adds
// only writers whose message verified (a forger's writer never does: it has no valid MAC for its
// own GUID), so the run's own writers fit (a node has one peer writer, the coordinator one per
// node); beyond kCapacity add() refuses and the caller looks the GUID up each time (still correct,
// an allocation per message). Cyclone never reuses a publication handle.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>

#include "transport/message_mac.h"

namespace rths::transport {

class WriterGuids {
 public:
  static constexpr std::size_t kCapacity = 64;

  // The GUID added for `handle`, or null. Valid as long as this object.
  const WriterGuid* find(std::uint64_t handle) const {
    const std::size_t n = count_.load(std::memory_order_acquire);
    for (std::size_t i = 0; i < n; ++i)
      if (entries_[i].handle == handle) return &entries_[i].guid;
    return nullptr;
  }

  // Remembers `guid` for `handle`; false when full (nothing changes). Adding a handle twice keeps
  // the first.
  bool add(std::uint64_t handle, const WriterGuid& guid) {
    std::lock_guard lock(add_mutex_);
    if (find(handle)) return true;
    const std::size_t n = count_.load(std::memory_order_relaxed);
    if (n == kCapacity) return false;
    entries_[n] = Entry{handle, guid};
    count_.store(n + 1, std::memory_order_release);
    return true;
  }

  std::size_t size() const { return count_.load(std::memory_order_acquire); }

 private:
  struct Entry {
    std::uint64_t handle = 0;
    WriterGuid guid{};
  };
  std::array<Entry, kCapacity> entries_{};
  std::atomic<std::size_t> count_{0};
  std::mutex add_mutex_;
};

}  // namespace rths::transport
