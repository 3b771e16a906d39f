#pragma once
// Bode data of the actuator channel (command -> measured displacement): the frequency response
// measured from the record against the identified and the declared model's.
//
//   measured  H1(f) = S_uy(f) / S_uu(f), u the command and y the measured displacement, by Welch
//             averaging (evidence.h transfer_estimate: Hann window, 50 % overlap), with the
//             coherence gamma^2(f) = |S_uy|^2 / (S_uu S_yy).
//   band      the longest run of frequency bins where gamma^2 >= min_coherence: outside it the
//             record does not determine H (the command does not excite it, or noise and
//             nonlinearity dominate); only the band is kept and plotted.
//   models    each model's frequency response as its simulation (model.h predict) realises it:
//               H(f) = gain e^{-i w tau} F(w) B(w),   w = 2 pi f,
//               F(w) = (1 - a) / (1 - a e^{-i w dt}), a = exp(-dt / T)   (first-order lag, exact
//                      for the model's recursion; 1 when absent),
//               B(w) = wn^2 / (wn^2 - v^2 + 2 i zeta wn v), v = (2 / dt) tan(w dt / 2)
//                      (the Tustin second-order lag, exact for the model's biquad; 1 when absent).
//             A time-varying delay or gain enters at its mean (the constant part). Backlash,
//             velocity saturation and the stroke limit depend on the amplitude, not the frequency,
//             and offsets do not pass the command: they are left out and named in `left_out`. The
//             linear interpolation of a fractional delay is taken as exact.
// Units: frequency Hz; amplitude ratio mm/mm (measured displacement per commanded, so 1 = the
// command realised in full); phase degrees, negative = lag, unwrapped from the lowest frequency.

#include <complex>
#include <filesystem>
#include <string>
#include <vector>

#include "identify/model/model.h"

namespace rths::identify {

struct BodeCurve {
  std::string title;
  std::vector<double> amplitude, phase_deg;  // one per BodeData::frequency
  std::vector<std::string> left_out;         // stages with no frequency response
};

struct BodeData {
  std::vector<double> frequency;                        // Hz, within the band
  std::vector<double> amplitude, phase_deg, coherence;  // measured (H1 and gamma^2)
  double band_low = 0.0, band_high = 0.0;               // Hz
  double min_coherence = 0.9;
  std::size_t segment = 0, segments = 0;  // Welch segment length (samples) and count
  std::vector<BodeCurve> models;
};

// The frequency response above of an actuator (measured channel) model at `frequency` (Hz), for
// a record of step dt. Throws std::invalid_argument for a force-channel model.
std::complex<double> actuator_response(const ChannelModel& model, double frequency, double dt);
// The stages of `model` that actuator_response leaves out (by effect name).
std::vector<std::string> actuator_response_left_out(const ChannelModel& model);

struct BodeModel {
  std::string title;
  const ChannelModel* model = nullptr;
};

// Welch segment: the largest power of two <= samples / 8, between 64 and 16384 samples.
// Throws std::invalid_argument when the signals are not the measured channel or too short
// (< 512 samples), or when no bin reaches min_coherence.
BodeData actuator_bode(const ChannelSignals& signals, const std::vector<BodeModel>& models,
                       double min_coherence = 0.9);

// Three panels (amplitude ratio, on a log axis when it spans more than a decade; phase in
// degrees; coherence), frequency on a log axis over the band, the measured estimate and each model;
// the PNG and the SVG beside it (util/plot.h). Throws std::runtime_error naming the file.
void write_bode_plot(const BodeData& bode, const std::filesystem::path& png);

}  // namespace rths::identify
