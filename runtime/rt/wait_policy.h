#pragma once
// How a real-time loop waits for its next absolute deadline (the "sleep" of read -> update ->
// write -> sleep), as a unit of its own like ros2_control's sleeping policies.
//
//   SLEEP            clock.sleep_until(deadline). Cheapest on CPU; wakes up as late as the kernel
//                    timer and scheduler make it (tens of us here, millisecond tails under load).
//   SLEEP_THEN_SPIN  sleep until deadline - spin_margin, then read the clock until it reaches the
//                    deadline. Trades up to spin_margin of one core per period for a wake-up
//                    that no longer depends on the timer's lateness, only on preemption.
//   SPIN             read the clock until the deadline; burns the core all the time. Only for a
//                    machine with a core to spare for the loop.
// Input: an absolute deadline (ns, the clock's own time base). Output: returns at or after it.
// Real-time safe: no allocation, no lock, no system call but the clock's.

#include <cstdint>
#include <string>

namespace rths::runtime {

class PacingClock;

enum class WaitPolicyKind { kSleep, kSleepThenSpin, kSpin };

struct WaitPolicy {
  WaitPolicyKind kind = WaitPolicyKind::kSleep;
  std::int64_t spin_margin_ns = 200'000;  // SLEEP_THEN_SPIN only; @pre >= 0
};

// "sleep", "sleep_then_spin", "spin".
std::string to_string(WaitPolicyKind kind);

// Returns once clock.now_ns() >= deadline_ns (immediately when it already is).
void wait_until(PacingClock& clock, std::int64_t deadline_ns, const WaitPolicy& policy);

}  // namespace rths::runtime
