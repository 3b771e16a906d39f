#include "runtime/rt/wait_policy.h"

#include "runtime/rt/clock.h"

namespace rths::runtime {

std::string to_string(WaitPolicyKind kind) {
  switch (kind) {
    case WaitPolicyKind::kSleep: return "sleep";
    case WaitPolicyKind::kSleepThenSpin: return "sleep_then_spin";
    case WaitPolicyKind::kSpin: return "spin";
  }
  return "unknown";
}

void wait_until(PacingClock& clock, std::int64_t deadline_ns, const WaitPolicy& policy) {
  switch (policy.kind) {
    case WaitPolicyKind::kSleep:
      if (clock.now_ns() < deadline_ns) clock.sleep_until_ns(deadline_ns);
      return;
    case WaitPolicyKind::kSleepThenSpin: {
      const std::int64_t wake = deadline_ns - policy.spin_margin_ns;
      if (clock.now_ns() < wake) clock.sleep_until_ns(wake);
      while (clock.now_ns() < deadline_ns) {}
      return;
    }
    case WaitPolicyKind::kSpin:
      while (clock.now_ns() < deadline_ns) {}
      return;
  }
}

}  // namespace rths::runtime
