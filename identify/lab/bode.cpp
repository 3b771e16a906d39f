#include "identify/lab/bode.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "identify/fit/evidence.h"
#include "util/plot.h"

namespace rths::identify {
namespace {

constexpr double kDegrees = 180.0 / std::numbers::pi;

// Model parameters by name (base and effects); missing = fallback.
double value_or(const ChannelModel& model, std::optional<Effect> effect, const std::string& name,
                const SignalScales& scales, double fallback) {
  return model.param(effect, name, scales).value_or(fallback);
}

std::string format_hz(double f) {
  std::ostringstream out;
  out.precision(f < 1.0 ? 2 : 3);
  out << f;
  return out.str();
}

}  // namespace

std::vector<std::string> actuator_response_left_out(const ChannelModel& model) {
  std::vector<std::string> out;
  for (Effect e : {Effect::kBacklash, Effect::kVelocitySaturation, Effect::kStrokeLimit,
                   Effect::kOffsetDrift}) {
    if (model.has(e)) out.push_back(effect_name(e));
  }
  return out;
}

std::complex<double> actuator_response(const ChannelModel& model, double frequency, double dt) {
  if (model.channel != Channel::kMeasured) {
    throw std::invalid_argument("actuator_response: a model of the measured (actuator) channel");
  }
  if (!(dt > 0.0)) throw std::invalid_argument("actuator_response: dt must be > 0");
  // Parameter specs do not depend on the scales for the names read here; unit scales will do.
  SignalScales scales;
  scales.dt = dt;
  const double w = 2.0 * std::numbers::pi * frequency;
  const double gain = value_or(model, std::nullopt, "gain", scales, 1.0);
  const double delay = std::max(0.0, value_or(model, Effect::kDelay, "delay", scales, 0.0));
  std::complex<double> h = gain * std::polar(1.0, -w * delay);
  if (model.has(Effect::kFirstOrder)) {
    const double t = value_or(model, Effect::kFirstOrder, "time_constant", scales, 0.0);
    const double a = std::exp(-dt / std::max(t, 1e-12));
    h *= (1.0 - a) / (1.0 - a * std::polar(1.0, -w * dt));
  }
  if (model.has(Effect::kSecondOrder)) {
    const double wn = value_or(model, Effect::kSecondOrder, "natural_frequency", scales, 1.0);
    const double zeta = value_or(model, Effect::kSecondOrder, "damping_ratio", scales, 0.7);
    const double v = 2.0 / dt * std::tan(0.5 * w * dt);  // Tustin frequency warping
    h *= wn * wn / std::complex<double>(wn * wn - v * v, 2.0 * zeta * wn * v);
  }
  return h;
}

namespace {

// The longest run of bins [begin, end) whose coherence reaches min_coherence; empty when none.
std::pair<std::size_t, std::size_t> coherent_band(const TransferEstimate& h, double min_coherence) {
  std::size_t best_begin = 0, best_end = 0;
  for (std::size_t k = 0; k < h.frequency.size();) {
    if (h.coherence[k] < min_coherence) {
      ++k;
      continue;
    }
    std::size_t end = k;
    while (end < h.frequency.size() && h.coherence[end] >= min_coherence) ++end;
    if (end - k > best_end - best_begin) {
      best_begin = k;
      best_end = end;
    }
    k = end;
  }
  return {best_begin, best_end};
}

BodeCurve model_curve(const BodeModel& m, const std::vector<double>& frequency, double dt) {
  BodeCurve curve;
  curve.title = m.title;
  curve.left_out = actuator_response_left_out(*m.model);
  double previous = 0.0;
  for (double f : frequency) {
    const std::complex<double> r = actuator_response(*m.model, f, dt);
    curve.amplitude.push_back(std::abs(r));
    // Unwrapped: the step from the previous frequency taken within (-180, 180] degrees.
    double phase = std::arg(r) * kDegrees;
    if (!curve.phase_deg.empty()) {
      phase = previous + std::remainder(phase - previous, 360.0);
    }
    curve.phase_deg.push_back(phase);
    previous = phase;
  }
  return curve;
}

}  // namespace

BodeData actuator_bode(const ChannelSignals& signals, const std::vector<BodeModel>& models,
                       double min_coherence) {
  if (signals.channel != Channel::kMeasured) {
    throw std::invalid_argument("Bode data: the measured (actuator) channel only");
  }
  if (signals.size() < 512) {
    throw std::invalid_argument("Bode data: at least 512 samples needed, got " +
                                std::to_string(signals.size()));
  }
  std::size_t segment = 64;
  while (segment * 2 <= signals.size() / 8 && segment < 16384) segment *= 2;
  const TransferEstimate h = transfer_estimate(signals.input, signals.target, signals.dt, segment);

  const auto [best_begin, best_end] = coherent_band(h, min_coherence);
  if (best_end == best_begin) {
    throw std::invalid_argument("Bode data: no frequency where the coherence reaches " +
                                std::to_string(min_coherence));
  }
  BodeData out;
  out.min_coherence = min_coherence;
  out.segment = segment;
  out.segments = h.segments;
  out.band_low = h.frequency[best_begin];
  out.band_high = h.frequency[best_end - 1];
  for (std::size_t k = best_begin; k < best_end; ++k) {
    out.frequency.push_back(h.frequency[k]);
    out.amplitude.push_back(h.magnitude[k]);
    out.phase_deg.push_back(h.phase[k] * kDegrees);
    out.coherence.push_back(h.coherence[k]);
  }
  for (const auto& m : models) out.models.push_back(model_curve(m, out.frequency, signals.dt));
  return out;
}

void write_bode_plot(const BodeData& bode, const std::filesystem::path& png) {
  const std::string band = format_hz(bode.band_low) + "-" + format_hz(bode.band_high) + " Hz";
  std::ostringstream coherence_text;
  coherence_text << bode.min_coherence;
  util::PlotSpec amplitude, phase, coherence;
  amplitude.title = "actuator, command -> measured displacement: band " + band +
                    " (coherence >= " + coherence_text.str() + ")";
  phase.title = "measured: H1 = S_uy / S_uu, Welch, " + std::to_string(bode.segments) +
                " Hann segments of " + std::to_string(bode.segment) + " samples, 50 % overlap";
  amplitude.ylabel = "amplitude ratio (mm/mm)";
  phase.ylabel = "phase (deg)";
  coherence.ylabel = "coherence (-)";
  coherence.xlabel = "frequency (Hz)";
  coherence.y_min = std::min(bode.min_coherence, 0.9) - 0.05;
  coherence.y_max = 1.01;
  amplitude.series.push_back({"measured (H1)", bode.frequency, bode.amplitude});
  phase.series.push_back({"measured (H1)", bode.frequency, bode.phase_deg});
  coherence.series.push_back({"measured", bode.frequency, bode.coherence});
  for (const auto& m : bode.models) {
    std::string title = m.title;
    if (!m.left_out.empty()) {
      title += " (without";
      for (const auto& l : m.left_out) title += " " + l;
      title += ")";
    }
    amplitude.series.push_back({title, bode.frequency, m.amplitude});
    phase.series.push_back({title, bode.frequency, m.phase_deg});
  }
  // A log amplitude axis when the curves span more than a decade (gnuplot labels only the
  // decades); a linear one from zero otherwise.
  double lowest = 1e300, highest = 0.0;
  for (const auto& series : amplitude.series) {
    for (double a : series.y) {
      if (a > 0.0 && std::isfinite(a)) {
        lowest = std::min(lowest, a);
        highest = std::max(highest, a);
      }
    }
  }
  amplitude.log_y = highest > 10.0 * lowest;
  if (highest > 0.0) {
    amplitude.y_min = amplitude.log_y ? 0.8 * lowest : 0.0;
    amplitude.y_max = amplitude.log_y ? 1.25 * highest : 1.1 * highest;
  }
  // The legends sit outside, right: a coherence legend as wide as the others keeps the three
  // panels' frequency axes aligned.
  std::size_t widest = 0;
  for (const auto& series : amplitude.series) widest = std::max(widest, series.title.size());
  coherence.series.front().title.resize(widest, ' ');
  for (auto* p : {&amplitude, &phase, &coherence}) {
    p->log_x = true;
    p->x_min = bode.band_low;
    p->x_max = bode.band_high;
    p->height = 380;
  }
  util::write_png_panels({amplitude, phase, coherence}, png);
}

}  // namespace rths::identify
