#include "identify/fit/evidence.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace rths::identify {

Evidence residual_evidence(const ChannelSignals& signals, std::span<const double> prediction) {
  Evidence e;
  const std::size_t n = signals.size();
  if (prediction.size() != n) throw std::invalid_argument("residual_evidence: sizes differ");
  std::vector<double> residual(n), sign(n), cubed(n);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    residual[i] = signals.target[i] - prediction[i];
    sum += residual[i] * residual[i];
    sign[i] = signals.velocity[i] > 0.0 ? 1.0 : (signals.velocity[i] < 0.0 ? -1.0 : 0.0);
    cubed[i] = signals.input[i] * signals.input[i] * signals.input[i];
  }
  e.residual_rms = n ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
  e.corr_input = correlation(residual, signals.input);
  e.corr_velocity = correlation(residual, signals.velocity);
  e.corr_velocity_sign = correlation(residual, sign);
  e.corr_input_cubed = correlation(residual, cubed);
  e.corr_acceleration = correlation(residual, signals.acceleration);
  e.input_to_residual = cross_correlation(signals.input, residual, signals.dt, 0.2);
  const auto spectrum = amplitude_spectrum(residual, signals.dt);
  double total = 0.0, low = 0.0, best = -1.0;
  for (std::size_t k = 1; k < spectrum.amplitude.size(); ++k) {
    const double power = spectrum.amplitude[k] * spectrum.amplitude[k];
    total += power;
    if (spectrum.frequency[k] < 1.0) low += power;
    if (spectrum.amplitude[k] > best) {
      best = spectrum.amplitude[k];
      e.dominant_frequency = spectrum.frequency[k];
    }
  }
  e.low_frequency_share = total > 0.0 ? low / total : 0.0;
  return e;
}

}  // namespace rths::identify
