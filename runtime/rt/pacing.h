#pragma once
// Real-time pacing with absolute deadlines (the "sleep" unit of a read -> update -> write -> sleep
// loop). Deadline k = start + k * period on CLOCK_MONOTONIC; the schedule never drifts and is never
// silently re-based: a late step is counted as an overrun and the next deadline stays on the grid.
//
//   wait(k): if now > deadline_k on entry -> overrun (the previous step ran past its slot), no
//   wait;
//            else wait until deadline_k with the WaitPolicy (sleep, sleep then spin, spin).
//   returns  lateness = wake-up time - deadline_k (s, >= 0 up to clock jitter), overrun flag.
// Real-time safe: no allocation. The clock is an interface so the unit is tested with a fake one.

#include <cstdint>

#include "runtime/rt/clock.h"
#include "runtime/rt/wait_policy.h"

namespace rths::runtime {

struct PaceResult {
  double lateness = 0.0;  // s
  bool overrun = false;
};

class Pacer {
 public:
  // @pre period > 0 (s)
  Pacer(PacingClock& clock, double period, WaitPolicy policy = {});
  // Deadline 0 = now. Also sets this thread's timer slack to 1 ns (Linux default 50 us).
  void start();
  PaceResult wait(std::int64_t step);
  std::int64_t deadline_ns(std::int64_t step) const;
  std::uint64_t overruns() const { return overruns_; }
  double max_lateness() const { return max_lateness_; }
  std::uint64_t worst_overrun_streak() const { return worst_streak_; }

 private:
  PacingClock& clock_;
  WaitPolicy policy_;
  std::int64_t period_ns_;
  std::int64_t start_ns_ = 0;
  std::uint64_t overruns_ = 0;
  std::uint64_t streak_ = 0, worst_streak_ = 0;
  double max_lateness_ = 0.0;
};

}  // namespace rths::runtime
