#pragma once
// One range rule per quantity a user types: flags, config fields and Python arguments all check
// a number against the same rule, where it is parsed, and refuse it with one message shape:
//   "<name> = <value> <unit> is outside <range> <unit> (<what the quantity is>)[; <hint>]"
// e.g. "--dt = 1e-09 s is outside [1e-06, 1] s (an integration step)".
//
// Quantity         allowed                      unit  why
// kLag             [0, 1]                       s     actuator and network lags are ms to tens of ms;
//                                                     a larger number is almost always ms typed as s
// kLongLag         [0, 3600]                    s     a lag with allow_long_lag: true
// kStep            [1e-6, 1]                    s     integration and sampling steps (1 us .. 1 s)
// kPeriod          (0, 50]                      s     natural periods (tall buildings are under 10 s)
// kDampingRatio    [0, 1]                       -     0.05 = 5 % of critical
// kFraction        [0, 1]                       -     shares, probabilities and fractions of a step
// kCount           [1, 2^31 - 1]                -     how many of something (steps, folds, answers)
// kTimeout         (0, 86400]                   s     how long to wait (a day at most)
// kCpu             [0, CPUs of this machine - 1] -    a CPU index that exists here
// kMotionScale     [0, 100]                     -     a factor on a ground motion
// kDdsDomain       [0, 232]                     -     Cyclone DDS domain ids
// kDays            [1, 36500]                   d     certificate validity
// kFrequency       (0, 1e7]                     Hz    sample and servo rates
// kFifoPriority    [1, 98]                      -     SCHED_FIFO priorities; 99 is the kernel's own
//                                                     (migration, watchdog), which must preempt a run
//
// A value that is not finite (nan, inf) is outside every range. An empty name drops "<name> = "
// (CLI11 puts the flag in front of a validator's message itself).

#include <string>
#include <string_view>

namespace rths::study {

enum class Quantity {
  kLag,
  kLongLag,
  kStep,
  kPeriod,
  kDampingRatio,
  kFraction,
  kCount,
  kTimeout,
  kCpu,
  kMotionScale,
  kDdsDomain,
  kDays,
  kFrequency,
  kFifoPriority,
};

struct Range {
  double min = 0, max = 0;
  bool min_open = false, max_open = false;  // open: the bound itself is outside
  std::string_view unit;                    // "s", "Hz", "" for a ratio or a count
  std::string_view what;                    // "an integration step"
  bool integer = false;                     // counts, CPUs, ids: whole numbers only

  bool contains(double value) const;
  std::string text() const;  // "[1e-06, 1] s", "(0, 50] s", "[1, 2147483647]"
};

// The rule of a quantity (kCpu: the CPUs configured on this machine).
Range range_of(Quantity quantity);

// `value` when it is inside the quantity's range; else throws std::invalid_argument naming `name`
// (a flag "--dt", a field "integrator.dt", an argument "dt_s"), the value and the range.
double check_range(Quantity quantity, double value, std::string_view name);
// The same for a whole number (counts, CPUs, ids, days).
int check_range(Quantity quantity, long long value, std::string_view name);

// The message check_range throws, or empty when `value` is inside.
std::string range_violation(Quantity quantity, double value, std::string_view name);

// A lag: kLongLag with `allow_long_lag`, else kLag (whose message then names allow_long_lag).
double check_lag(double seconds, std::string_view name, bool allow_long_lag = false);

}  // namespace rths::study
