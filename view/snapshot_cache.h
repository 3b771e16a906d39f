#pragma once
// SnapshotCache: one serialised snapshot shared by every /api/snapshot client, rebuilt at most
// once per interval, so clients looping on it cost the feed (whose lock the record's writer
// thread takes for every entry) and the machine the loop runs on a bounded share of one CPU,
// whatever their number or rate and however long the run.
//
// Inputs: `build` (the whole feed as JSON text; called on a server thread, never the loop's),
// `period` (ms) between builds, `now` (the clock) and `cpu` (the building thread's CPU time;
// both the system's unless a test steps its own).
// Interval: max(period, kCostRatio x the last build's CPU time). CPU time, not wall time: a build
// preempted on a busy machine is not taken for a costly one. A feed's snapshot grows with the
// run (about 0.5 MB and 4.5 ms to build per 10 s of samples at 1 kHz), so a fixed period alone
// would let a 10-minute run's clients take a whole core; with the ratio the builds take at most
// 1 / kCostRatio of one CPU and a copy is older only while a build costs more than period /
// kCostRatio.
// Outputs: get(): the newest copy, at most one interval old when it was not being rebuilt; while
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

#include "runtime/rt/clock.h"

namespace rths::view {

class SnapshotCache {
 public:
  using Clock = std::function<std::chrono::steady_clock::time_point()>;
  using CpuClock = std::function<std::chrono::nanoseconds()>;  // the calling thread's CPU time
  static constexpr int kCostRatio = 20;  // interval / a build's CPU time, at least: 5 % of a CPU

  SnapshotCache(
      std::function<std::string()> build, std::chrono::milliseconds period,
      Clock now = [] { return std::chrono::steady_clock::now(); },
      CpuClock cpu = [] { return std::chrono::nanoseconds(runtime::thread_cpu_ns()); });

  std::shared_ptr<const std::string> get();
  std::uint64_t builds() const;
  std::uint64_t served() const;

 private:
  std::function<std::string()> build_;
  std::chrono::milliseconds period_;
  Clock now_;
  CpuClock cpu_;
  std::chrono::steady_clock::duration interval_;  // until the next build: max(period, ratio x cost)
  mutable std::mutex mutex_;
  std::condition_variable built_cv_;
  std::shared_ptr<const std::string> copy_;
  std::chrono::steady_clock::time_point built_at_{};
  bool building_ = false;
  std::uint64_t builds_ = 0, served_ = 0;
};

}  // namespace rths::view
