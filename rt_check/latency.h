#pragma once
// The wake-up lateness of a paced thread, measured the way cyclictest does, and its statistics.
//
//   measure_wakeups  one thread per CPU, pinned to it, timer slack 1 ns, the loop's own pacing
//                    (runtime::MonotonicClock: clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC)
//                    to deadlines on the grid start + k / rate_hz for `seconds`;
//                    lateness = wake-up - deadline (s). After a late wake-up the next deadline is
//                    the first grid point still ahead, so a stall counts once, with its length.
//                    /dev/cpu_dma_latency is held at 0 meanwhile when permitted (as a run holds
//                    it).
//   LatencyStats     all CPUs pooled: median, p99, p99.99, max; stalls (wake-ups later than x)
//                    per minute of measurement, all CPUs summed (a stall on any CPU can stop a
//                    run: the loop's CPU stalls the coordinator, another CPU a node);
//                    the overrun fraction a loop doing `work` s per step would see:
//                    sum over wake-ups of floor((lateness + work) / period) deadlines passed,
//                    over the deadlines of one CPU's measurement times the CPUs.

#include <atomic>
#include <cstdint>
#include <vector>

namespace rths::rt_check {

struct WakeupSamples {
  std::vector<int> cpus;
  std::vector<std::vector<double>> lateness;  // per cpus[i], s, in order
  double rate_hz = 0.0;
  double seconds = 0.0;
  bool dma_latency_held = false;
};

// @pre rate_hz > 0, seconds > 0, cpus non-empty. Throws std::runtime_error naming a CPU that
// cannot be had (not online, not allowed).
WakeupSamples measure_wakeups(const std::vector<int>& cpus, double rate_hz, double seconds);

// The same, measured while something else runs: until `stop` is set (or max_seconds passed);
// the samples' seconds is then the time measured. For a witness of the machine's stalls during
// a run, beside it.
WakeupSamples measure_wakeups_until(const std::vector<int>& cpus, double rate_hz,
                                    const std::atomic<bool>& stop, double max_seconds);

class LatencyStats {
 public:
  explicit LatencyStats(const WakeupSamples& samples);
  std::uint64_t wakeups() const { return sorted_.size(); }
  double minutes() const { return minutes_; }  // of measurement, all CPUs summed
  double rate_hz() const { return rate_hz_; }
  double seconds() const { return seconds_; }
  double quantile(double q) const;  // s; 0 without samples
  double max() const { return sorted_.empty() ? 0.0 : sorted_.back(); }
  std::uint64_t count_over(double lateness) const;  // wake-ups later than lateness (s)
  double stalls_per_minute(double lateness) const;  // count_over / minutes()
  double overrun_fraction(double work) const;       // work: s of the step after the wake-up

 private:
  std::vector<double> sorted_;
  double minutes_ = 0.0, rate_hz_ = 0.0, seconds_ = 0.0;
  std::size_t cpus_ = 0;
};

}  // namespace rths::rt_check
