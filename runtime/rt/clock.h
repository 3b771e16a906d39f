#pragma once
// The clock a real-time loop paces and waits on: an interface, so that pacing and wait policies
// are tested with a fake clock, and CLOCK_MONOTONIC for the real thing.
// Times are integer nanoseconds on the clock's own monotonic time base. Real-time safe: no
// allocation, no lock, no system call but the clock's.

#include <cstdint>

namespace rths::runtime {

// The house's one monotonic clock: CLOCK_MONOTONIC now, ns. Every deadline, wait and age the
// runtime, the node loop and the controller link measure is on it.
std::int64_t monotonic_ns();

// The CPU time the calling thread has run, ns (CLOCK_THREAD_CPUTIME_ID): never the time it waited
// for a CPU, so a loaded machine does not move it. A loop's own work per step and a thread's
// budget for itself are measured on it.
std::int64_t thread_cpu_ns();

class PacingClock {
 public:
  virtual ~PacingClock() = default;
  virtual std::int64_t now_ns() = 0;                       // monotonic
  virtual void sleep_until_ns(std::int64_t deadline) = 0;  // absolute, same clock
};

// CLOCK_MONOTONIC with clock_nanosleep(TIMER_ABSTIME), retried on EINTR.
class MonotonicClock final : public PacingClock {
 public:
  std::int64_t now_ns() override;
  void sleep_until_ns(std::int64_t deadline) override;
};

}  // namespace rths::runtime
