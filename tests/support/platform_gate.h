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
//     text       "wake-up lateness at 1000 Hz over 0.5 s on 2 CPUs: p99 0.08 ms, max 3.9 ms;
//                CPU share 0.98"
//
//   measure_cpu_share(seconds) -> share in (0, 1]: one busy thread per CPU this process may
//     use, each spinning for `seconds` of wall time; the mean over them of its CPU time
//     (CLOCK_THREAD_CPUTIME_ID) over that wall time. A sleeper's wake-up lateness barely moves
//     beside busy loops at its priority (the scheduler wakes a sleeper first), while a run's loop
//     and its node processes share the CPUs with them: this figure sees them. With k other busy
//     threads on n CPUs it is about n / (n + k). Measured on this project's 2-core VM
//     (2026-12-08 01:28-01:45 UTC, 0.25 s, this loop in a stand-alone probe): 0.95-0.98 in
//     the moments no other work ran; 0.45-0.58 most of the time (0.14-0.72 in all, 142
//     samples) beside other sessions' two compilers; 0.07-0.29 beside two CPU burners
//     (`sh -c 'while :; do :; done'` twice) and those compilers.
//   kLoadedCpuShare   0.7: under it other busy threads took more than the CPUs' slack (two busy
//     threads on two CPUs give 0.5); a timing failure beside it is the machine's.
//   measure_platform(rate_hz, seconds) also measures the CPU share (kCpuShareSeconds) and names
//     it in its text.
//
//   StallWitness   the same measurement just before a run (the constructor, `seconds` long) and
//                  just after it (finish(), as long), never during: the run's own processes then
//                  cannot move it, so a regression that burns CPU is not read as a loaded
//                  machine. finish() gives the worse of the two (by longest stall; the lower
//                  CPU share). A run's timing failure is the machine's when the witness saw a
//                  stall of that size around it (a load that came and went within the run is
//                  missed: then the failure is the code's, which a rerun tells apart); without
//                  one it is the code's.

#include <optional>
#include <string>

#include "rt_check/latency.h"

namespace rths::test {

struct MeasuredPlatform {
  double p99 = 0.0;  // s
  double max = 0.0;  // s
  std::optional<rt_check::LatencyStats> stalls;
  double cpu_share = 1.0;  // measure_cpu_share, the lower of before and after for a witness
  std::string text;
};

inline constexpr double kLoadedCpuShare = 0.7;
inline constexpr double kCpuShareSeconds = 0.25;  // s of spinning per measurement

double measure_cpu_share(double seconds);
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
