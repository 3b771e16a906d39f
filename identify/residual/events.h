#pragma once
// Events located in time: what a residual holds for a moment of the record (a held reading,
// isolated spikes, a few seconds of something, a change from some time on), found by an outlier
// and a change-point search rather than by its power over the whole record.
//
// Input: samples t_j (s) at step dt, the channel's reading y_j, the model's prediction p_j and
// r_j = y_j - p_j (the channel's unit), and sigma (unit): the floor the record's own noise sets.
//   held_sample  a run of at least kMinHeldSamples identical readings (a sample-and-hold that
//                stopped updating, a frozen sensor) over which the residual's RMS exceeds
//                kEventFactor x sigma (the model moved on while the reading did not).
//   spike        d_j = r_j - the running median of r over kMedianSpan samples (centred); s = max(sigma,
//                1.4826 MAD(d)); samples with |d_j| > kSpikeSigmas x s, grouped where at most 2
//                samples apart, each group of at most kMaxSpikeSamples one spike at its largest
//                |d| (size: that d, unit).
//   change       with the spikes' samples set to their running median and the held runs to 0,
//   points       the record in blocks of kBlockSeconds; per block b the residual's mean square
//                e_b, the prediction's q_b, and what the record leaves there without an event,
//                x_b = max(sigma^2, m ((1 - f) + f q_b / mean q)): a residual between one of a
//                steady level (f = 0: a ripple, the noise) and one in proportion to the motion
//                (f = 1: the model's error), f on a grid of kExpectedGrid + 1 values in [0, 1],
//                m = the median of e_b over the shape, the pair leaving the least median
//                |ln(e_b / x_b)| (medians: an event in a few blocks does not move them). z_b = ln(e_b / x_b) is cut by binary segmentation: a segment
//                [i, k) splits at the m maximising the CUSUM statistic
//                |mean z[i, m) - mean z[m, k)| sqrt(n1 n2 / (n1 + n2)) / s_z (s_z = 1.4826 MAD
//                of z's adjacent differences / sqrt 2) when that exceeds kChangeSigmas, segments of
//                at least 2 blocks. A segment is an event when sum e / sum x over it is at least
//                kEventFactor^2; adjacent ones merge. One that runs to the record's end:
//                shorter than kMinStepSeconds, none (a correct model's error gathers at the
//                record's end, residual_floor.h); else a step_change when its residual is mostly
//                its mean (mean^2 >= half its mean square; size: its mean less the mean before,
//                unit), or when it follows the motion ((sum r p)^2 >= kFollowsMotion sum r^2 sum
//                p^2: a gain that changed at that time) a capacity_drop where the reading falls
//                against the model (sum r p < 0), a step_change where it rises (size: sum r p /
//                sum p^2, measured / model - 1). Any other event is a burst.
// Each event's share: its samples' sum r^2 over the record's (for a spike, its d^2).
// Several events of a kind are each listed; at most kMaxEvents of each kind, the largest first.

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace rths::identify {

inline constexpr std::size_t kMinHeldSamples = 20;
inline constexpr double kEventFactor = 3.0;  // x sigma (RMS): kFloorFactor's
inline constexpr std::size_t kMedianSpan = 9;
inline constexpr double kSpikeSigmas = 10.0;
inline constexpr std::size_t kMaxSpikeSamples = 5;
inline constexpr double kBlockSeconds = 0.05;
inline constexpr double kChangeSigmas = 8.0;
inline constexpr double kMinStepSeconds = 2.0;
inline constexpr std::size_t kExpectedGrid = 20;
inline constexpr double kFollowsMotion = 0.5;  // squared correlation of r with p
inline constexpr std::size_t kMaxEvents = 20;

enum class EventKind { kHeldSample, kSpike, kBurst, kStepChange, kCapacityDrop };

struct ResidualEvent {
  EventKind kind = EventKind::kBurst;
  double start = 0.0, end = 0.0;  // s; a spike's are its largest sample's time
  double share = 0.0;             // of the residual's power over the record
  // Unit: a spike's d, an offset step's change, a held run's or a burst's RMS r; a gain's step
  // (capacity_drop, step_change following the motion): measured / model - 1.
  double size = 0.0;
  bool relative = false;  // size is measured / model - 1 (a gain's step), not in the unit
};

// @pre time, reading and prediction of the same size; dt > 0; sigma >= 0.
std::vector<ResidualEvent> find_events(std::span<const double> time,
                                       std::span<const double> reading,
                                       std::span<const double> prediction, double dt, double sigma);

// "held_sample", "spike", "burst", "step_change", "capacity_drop".
std::string event_name(EventKind kind);

}  // namespace rths::identify
