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
//   StallWitness   the same measurement beside a run: started before it, finish() after it
//                  gives what the machine did meanwhile. A run's timing failure is the machine's
//                  when the witness saw a stall of that size; without one it is the code's.

#include <atomic>
#include <future>
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
  // At most `max_seconds` of measurement (a run that outlives it is judged on what was seen).
  explicit StallWitness(double rate_hz = 1000.0, double max_seconds = 120.0);
  ~StallWitness();
  StallWitness(const StallWitness&) = delete;
  StallWitness& operator=(const StallWitness&) = delete;
  MeasuredPlatform finish();  // once

 private:
  double rate_hz_;
  std::atomic<bool> stop_{false};
  std::future<rt_check::WakeupSamples> samples_;
};

}  // namespace rths::test
