#pragma once
// Offline generator of measured-like lab data, built from the core blocks, containing effects a
// declared model may lack. For tests and demonstrations of `rths identify`.
//
// Command u_c(t) (m):
//   kChirp       amplitude sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)))         linear chirp f0 -> f1
//   kEarthquake  white noise (seeded) through two core TransferFunctionStage filters
//                (a 2nd-order low-pass at `corner_frequency`, zeta 0.6, and a 1st-order high-pass
//                at 0.2 Hz), times a rise-plateau-decay envelope, scaled to peak `amplitude`.
// Actuator (channel measured): core TimeShift(delay), or core TraceShift following
//   tau(t) = delay + delay_drift sin(2 pi t / duration) when delay_drift != 0 (a lag drifting over
//   the record: a warming servo-valve, network jitter) -> [core FirstOrderActuator(T)]
//   -> [core TransferFunctionStage wn^2 / (s^2 + 2 zeta wn s + wn^2)] with gain, then the
//   effects the core has no block for: backlash (play operator of total width b), velocity
//   saturation, a drifting gain 1 + gain_drift sin(2 pi t / duration), offset + drift (normalised
//   time s in [-1/2, 1/2]).
// Specimen (channel force), on the true realised displacement d and its velocity v:
//   core LinearSpring(k) or core BoucWen(k, uy, alpha, 1, 0.5) when bouc_wen_yield > 0,
//   + c v + F_c tanh(v / v_c) + k3 d^3 + m a + force offset
//   + stiffness_drift k sin(2 pi t / duration) d (a slowly drifting stiffness).
// Noise: Gaussian (seeded) on the measured displacement (m rms) and force (N rms); the command is
// clean. Output: MeasuredData in SI units, validated.

#include <cstdint>

#include "identify/model/data.h"

namespace rths::identify {

struct GeneratorSpec {
  enum class Command { kChirp, kEarthquake };
  Command command = Command::kChirp;
  double duration = 20.0;         // s
  double dt = 0.002;              // s
  double amplitude = 0.002;       // m, peak command
  double chirp_start = 0.3;       // Hz
  double chirp_end = 12.0;        // Hz
  double corner_frequency = 4.0;  // Hz, earthquake-like spectrum
  // actuator
  double delay = 0.012, gain = 1.0;
  double delay_drift = 0.0;  // s, amplitude of the delay's drift (<= delay)
  double gain_drift = 0.0;   // relative: the realised displacement times 1 + g sin(2 pi t / T)
  double first_order_time_constant = 0.0;  // s, 0 = absent
  double second_order_frequency = 0.0;     // Hz, 0 = absent
  double second_order_damping = 0.7;
  double backlash_width = 0.0;       // m
  double max_velocity = 0.0;         // m/s, 0 = no saturation
  double offset = 0.0, drift = 0.0;  // m
  // specimen
  double stiffness = 2.0e5;                              // N/m
  double damping = 0.0;                                  // N s/m
  double coulomb_force = 0.0, coulomb_velocity = 0.002;  // N, m/s
  double cubic_stiffness = 0.0;                          // N/m^3
  double mass = 0.0;                                     // kg
  double bouc_wen_yield = 0.0, bouc_wen_alpha = 0.1;     // m (0 = linear spring), -
  double force_offset = 0.0;                             // N
  // relative drift of the stiffness: + stiffness_drift k sin(2 pi t / duration) d (a warming or
  // cracking specimen)
  double stiffness_drift = 0.0;
  // noise
  double displacement_noise = 2.0e-6;  // m rms
  double force_noise = 2.0;            // N rms
  std::uint64_t seed = 1;
};

// Throws std::invalid_argument naming the field for non-positive duration/dt/amplitude or a
// record shorter than 200 samples.
MeasuredData generate_measured(const GeneratorSpec& spec);

}  // namespace rths::identify
