#pragma once
// Parametric models of the two measured channels and the library of effects they may contain.
//
// Channel `measured` (the actuator): input command u_c(t) (m) -> measured displacement (m):
//   x(t)  = u_c(t - tau(t))                 tau(t) = max(0, delay + D(s(t); delay_c))   (interpolated)
//   x    -> first-order lag    T dy/dt = x - y                  (exact for a held sample)
//        -> second-order lag   y'' + 2 zeta wn y' + wn^2 y = wn^2 x   (Tustin)
//        -> backlash / dead band of total width b (play operator)
//        -> velocity saturation |dy/dt| <= v_max
//        -> stroke limit y = clamp(y, -s, s) (the rod's ends, s either side of its centre)
//   u_m  = gain (1 + D(s(t); gain_c)) * y + offset + drift * s(t)
// Channel `force` (the specimen): input measured displacement d, velocity v, acceleration a
// (shifted by the force delay when present) -> force (N):
//   F = (k + D(s(t); k_c)) d + k3 d^3 + c v + F_c tanh(v / v_c) + m a + F_bw z + p
//       + offset + drift s
//   elasto-plastic element p (the bilinear specimen with the spring k as post-yield stiffness):
//   p_j = clamp(p_{j-1} + k_p (d_j - d_{j-1}), -F_y, F_y).
//   Bouc–Wen z (dimensionless, |z| <= 1), n = 1, beta = gamma = 1/2 over the drift increment:
//   dz/dd = (1 - |z| (sgn(dd z) + 1) / 2) / d_y, integrated exactly per step.
// s(t) = (t - t_mid) / duration is the normalised time, in [-1/2, 1/2].
// Slow drifts (time-varying delay, gain, stiffness) are zero-mean cosine series over the record:
//   D(s; c) = sum_{k=1..K} c_k cos(pi k (s + 1/2))
// (K = kDriftTerms), smooth, orthogonal over the record and free of a constant part, so the
// constant delay / gain / stiffness keeps its meaning as the record's mean.
// Bounds are physical: stiffness, damping, mass, friction and hysteretic forces >= 0; delays >= 0
// and shorter than half the record; time constants between a fifth of a sample step and 1 s and
// natural frequencies below Nyquist (finite bandwidth).
// Every effect is the parametric addition of its terms to the model; an effect absent from the
// model contributes nothing. All parameters are in SI units.

#include <cstddef>
#include <span>
#include <vector>

#include "identify/model/effects.h"
#include "identify/model/parameters.h"
#include "identify/model/signals.h"

namespace rths::identify {

// Model output over the whole record (the state runs from sample 0, at rest at the first input).
void predict(const ChannelModel& model, std::span<const double> params,
             const ChannelSignals& signals, std::vector<double>& out);
std::vector<double> predict(const ChannelModel& model, const ChannelSignals& signals);

// RMS(target - prediction) / std(target) over the given samples.
double normalised_error(std::span<const double> target, std::span<const double> prediction,
                        std::span<const std::size_t> samples);

}  // namespace rths::identify
