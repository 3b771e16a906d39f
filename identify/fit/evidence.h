#pragma once
// Evidence that a residual hides a missing effect: what it correlates with, where its energy is.
//
//   residual_evidence    for a channel's residual r = target - prediction: correlation of r with
//                        the input, the input's velocity, sign(velocity), the input cubed and the
//                        acceleration; the cross-correlation input -> residual; the residual
//                        spectrum's dominant frequency and the share of its power below 1 Hz.

#include <span>

#include "identify/model/model.h"
#include "identify/model/spectra.h"

namespace rths::identify {

struct Evidence {
  double corr_input = 0.0, corr_velocity = 0.0, corr_velocity_sign = 0.0, corr_input_cubed = 0.0;
  double corr_acceleration = 0.0;
  CrossCorrelation input_to_residual;
  double dominant_frequency = 0.0;   // Hz
  double low_frequency_share = 0.0;  // power below 1 Hz / total
  double residual_rms = 0.0;
};
Evidence residual_evidence(const ChannelSignals& signals, std::span<const double> prediction);

}  // namespace rths::identify
