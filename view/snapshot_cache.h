#pragma once
// SnapshotCache: one serialised snapshot shared by every /api/snapshot client, rebuilt at most
// once per `period`, so clients looping on it cost the feed (whose lock the record's writer
// thread takes for every entry) a bounded number of full snapshots per second, whatever their
// number or rate.
//
// Inputs: `build` (the whole feed as JSON text; called on a server thread, never the loop's),
// `period` (ms) between builds.
// Outputs: get(): the newest copy, at most `period` old when it was not being rebuilt; while
// one caller rebuilds, the others get the previous copy at once (the first callers wait for the
// first copy). builds(): how often `build` ran; served(): how many copies went out.
// Thread safety: every member from any thread.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

namespace rths::view {

class SnapshotCache {
 public:
  SnapshotCache(std::function<std::string()> build, std::chrono::milliseconds period);

  std::shared_ptr<const std::string> get();
  std::uint64_t builds() const;
  std::uint64_t served() const;

 private:
  std::function<std::string()> build_;
  std::chrono::milliseconds period_;
  mutable std::mutex mutex_;
  std::condition_variable built_cv_;
  std::shared_ptr<const std::string> copy_;
  std::chrono::steady_clock::time_point built_at_{};
  bool building_ = false;
  std::uint64_t builds_ = 0, served_ = 0;
};

}  // namespace rths::view
