#pragma once
// A period in a sensor's noise band: a hum the noise estimate would otherwise swallow.
//
// Input: one actuator path (actuator_path.h) after its channels were identified and judged. Per
// channel c (measured: the displacement read, m; force: the load cell's force, N) with target y,
// the reported model's prediction p (the final model without what the description beat,
// unexplained.h) and the residual r = y - p:
//   band      the model's input band f_b (Hz): the force channel's input cutoff
//             (ChannelSignals::input_cutoff, signals.h), on both channels: the force's input is
//             the displacement read, so above f_b that reading is its noise and no model fed by it
//             holds what lies there. No cutoff, no test.
//   above     r_a = r - lowpass(r, f_b) (signals.h zero_phase_lowpass): what the noise estimate
//             (sensors.h white_noise) and the floor's band noise (residual_floor.h) are made of.
//   period    r_a described (identify/residual/description.h describe_residual): its periodic test
//             alone, at a frequency above f_b, the only test accepted. That test takes a spectral
//             peak kPeakOverFloor x the median amplitude within kFloorBand Hz of it (a bin or a
//             few, far above their neighbours) and a sinusoid there that explains at least
//             kMinExplained of r_a's held-out variance (a stated share of the band's power).
//             White noise's largest of n bins (Rayleigh amplitudes) stands about
//             sqrt(2 ln n) / 1.18 x the median, 3.5 x for 5,000 bins: far below.
// Output: an `unexplained` entry on the sensor ("load cell N", "displacement sensor N") with kinds
// ["periodic"], its frequency (Hz) and amplitude (unit), and a note stating the sensor's white
// noise (sensors.h white_noise) without the period, sigma(r - the sinusoid), beside the figure
// with it. Not made where the channel's own description (describe_unexplained) already holds a
// period, nor where another channel of the path holds one within kSamePeriod of its frequency (a
// rod's ripple the specimen passes on to the load cell is the rod's): one period, one entry.

#include <optional>
#include <vector>

#include "identify/run/unexplained.h"

namespace rths::identify {

inline constexpr double kSamePeriod = 0.02;  // relative, on the frequency

// The period in `channel`'s noise band on `path` (above); none where the test finds none.
std::optional<Unexplained> period_in_noise_band(const ActuatorPath& path, Channel channel);

// describe_unexplained (unexplained.h), then each channel's period in its noise band where the
// rules above let it in.
std::vector<Unexplained> describe_with_noise_periods(const ActuatorPath& path);

}  // namespace rths::identify
