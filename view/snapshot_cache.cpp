#include "view/snapshot_cache.h"

#include <algorithm>

namespace rths::view {

SnapshotCache::SnapshotCache(std::function<std::string()> build, std::chrono::milliseconds period,
                             Clock now, CpuClock cpu)
    : build_(std::move(build)),
      period_(period),
      now_(std::move(now)),
      cpu_(std::move(cpu)),
      interval_(period) {}

std::shared_ptr<const std::string> SnapshotCache::get() {
  std::unique_lock lock(mutex_);
  const auto now = now_();
  const bool fresh = copy_ && now - built_at_ < interval_;
  if (fresh || (building_ && copy_)) {
    ++served_;
    return copy_;
  }
  if (building_) {  // the first copy is on its way
    built_cv_.wait(lock, [this] { return !building_; });
    ++served_;
    return copy_;
  }
  building_ = true;
  ++builds_;
  lock.unlock();
  const std::chrono::nanoseconds cpu_before = cpu_();
  std::shared_ptr<const std::string> made;
  try {
    made = std::make_shared<const std::string>(build_());
  } catch (...) {
    lock.lock();
    building_ = false;
    built_cv_.notify_all();
    throw;
  }
  const std::chrono::nanoseconds cost = cpu_() - cpu_before;
  lock.lock();
  copy_ = std::move(made);
  interval_ = std::max<std::chrono::steady_clock::duration>(period_, kCostRatio * cost);
  built_at_ = now_();
  building_ = false;
  ++served_;
  built_cv_.notify_all();
  return copy_;
}

std::uint64_t SnapshotCache::builds() const {
  std::lock_guard lock(mutex_);
  return builds_;
}

std::uint64_t SnapshotCache::served() const {
  std::lock_guard lock(mutex_);
  return served_;
}

}  // namespace rths::view
