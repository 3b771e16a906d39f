#pragma once
// The clock offset between the coordinator's host and a node's, from the one-way stamps of a
// run's answers (runtime/record/measurements.h LinkSeries one_way_down, one_way_up).
//
// Input: per answer, the one-way times down (command: node receive stamp - coordinator send
// stamp) and up (feedback: coordinator receive stamp - node send stamp), s, each on the two hosts'
// own clocks; the lag the node declares it injects each way (receive_lag, send_lag one_way_delay,
// s). With theta = node clock - coordinator clock:
//   down_i = d_down,i + q_down + theta,   up_i = d_up,i + q_up - theta
// and, for a path as fast one way as the other (NTP's assumption),
//   theta = (median(down - q_down) - median(up - q_up)) / 2.
// Output: theta and both ways' medians with the injection removed. `named` when |theta| >
// kMinClockOffset, or when a way's median with the injection removed is below
// -kNegativeTolerance, which no network does without an offset. Stamps alone cannot tell an
// offset from a path slower one way: `detail` says so. Nothing (nullopt) under kMinSamples answers.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace rths::identify {

struct ClockOffset {
  double offset = 0.0;                        // s, node clock - coordinator clock
  double down_median = 0.0, up_median = 0.0;  // s, the injection removed
  std::size_t samples = 0;
  bool named = false;
  std::string detail;  // the figures, in ms
};

inline constexpr double kMinClockOffset = 0.5e-3;     // s
inline constexpr double kNegativeTolerance = 0.1e-3;  // s
inline constexpr std::size_t kMinClockSamples = 20;

std::optional<ClockOffset> clock_offset(const std::vector<double>& down,
                                        const std::vector<double>& up, double injected_down,
                                        double injected_up);

}  // namespace rths::identify
