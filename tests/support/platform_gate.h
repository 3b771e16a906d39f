#pragma once
// This machine's scheduling now, measured with the project's own check (rt_check/latency.h:
// paced threads on every CPU this process may use, at the test's rate), so that a test of a
// real-time property sizes its windows and tolerances from what the machine does, and skips,
// printing what it measured, where the machine cannot hold the property at all. A busy machine
// then never fails a correct build; a quiet one still checks the property tightly.
//
//   measure_platform(rate_hz, seconds) -> MeasuredPlatform
//     p99, max   wake-up lateness (s) pooled over the CPUs; max is the longest stall seen
//     stalls     the statistics themselves (stalls_per_minute(x): wake-ups later than x s)
//     text       "wake-up lateness at 1000 Hz over 0.5 s on 2 CPUs: p99 0.08 ms, max 3.9 ms"
//
//   StallWitness   the same measurement just before a run (the constructor, `seconds` long) and
//                  just after it (finish(), as long), never during: the run's own processes then
//                  cannot move it, so a regression that burns CPU is not read as a loaded
//                  machine. finish() gives the worse of the two (by longest stall). A run's
//                  timing failure is the machine's when the witness saw a stall of that size
//                  around it (a load that came and went within the run is missed: then the
//                  failure is the code's, which a rerun tells apart); without one it is the code's.

#include <optional>
#include <string>

#include "rt_check/latency.h"

namespace rths::test {

struct MeasuredPlatform {
  double p99 = 0.0;  // s
  double max = 0.0;  // s
  std::optional<rt_check::LatencyStats> stalls;
  std::string text;
};

MeasuredPlatform measure_platform(double rate_hz, double seconds = 0.5);

class StallWitness {
 public:
  // Measures the machine now, for `seconds` at `rate_hz`.
  explicit StallWitness(double rate_hz = 1000.0, double seconds = 1.0);
  MeasuredPlatform finish();  // once: measures again, the worse of the two

 private:
  double rate_hz_, seconds_;
  MeasuredPlatform before_;
};

}  // namespace rths::test
