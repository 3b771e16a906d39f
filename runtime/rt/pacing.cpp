#include "runtime/rt/pacing.h"

#include <sys/prctl.h>

#include <cerrno>
#include <cmath>
#include <ctime>
#include <stdexcept>
#include <string>

namespace rths::runtime {

Pacer::Pacer(PacingClock& clock, double period, WaitPolicy policy)
    : clock_(clock), policy_(policy), period_ns_(std::llround(period * 1e9)) {
  if (!(period > 0))
    throw std::invalid_argument("pacing period must be > 0 s, got " + std::to_string(period));
}

void Pacer::start() {
  // Linux lets a normal thread's timer wake up to 50 us late (timer slack) to batch wake-ups; a
  // pacing loop wants its deadline, so ask for 1 ns (per thread; harmless where unsupported).
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  start_ns_ = clock_.now_ns();
}

std::int64_t Pacer::deadline_ns(std::int64_t step) const { return start_ns_ + step * period_ns_; }

PaceResult Pacer::wait(std::int64_t step) {
  const std::int64_t deadline = deadline_ns(step);
  PaceResult result;
  if (clock_.now_ns() > deadline) {
    result.overrun = true;
    ++overruns_;
    if (++streak_ > worst_streak_) worst_streak_ = streak_;
  } else {
    streak_ = 0;
    wait_until(clock_, deadline, policy_);
  }
  result.lateness = static_cast<double>(clock_.now_ns() - deadline) * 1e-9;
  if (result.lateness > max_lateness_) max_lateness_ = result.lateness;
  return result;
}

}  // namespace rths::runtime
