#pragma once
// A servo controller's tracking loop, as a lab's (and the RTHS benchmark's) controller runs it at
// the servo period h, as one delay stage: command r (m) in, measured displacement y (m) out.
//
//   x_k = P's displacement at t_k                  (P continuous, zero-order hold on u, exact)
//   y_k = x_k + noise_k                            (the displacement sensor the controller reads)
//   u_k = DA(C(AD(DA(F(AD(r_k))) - y_k)))          (F feedforward, C controller, both discrete)
//   P advances over [t_k, t_k + h] under u_k;  output x_k: the specimen's displacement, whose
//   force f_k (with the specimen's inertia and damping) is what the integrator gets back.
//   sensor_error() = noise_k: the actuator reports y_k as the realised displacement.
//   measure_force(f_k) = f_{k-d} + force noise_{k-d}: the load cell's reading reaches the
//   integrator d = force_delay_periods servo periods later (zero before the first d periods).
// AD/DA: saturation at +-range, quantisation to multiples of quantum (Converter; 0 = none).
// Noise: Gaussian, rms given, from one seeded generator (the same draws in every process):
// per period the displacement's draw, then the force's.
//
// Blocks (each step(x) -> y with explicit state, no allocation after construction):
//   DiscreteFilter  y = b(z^-1) / a(z^-1) x, direct form II transposed; a[0] = 1.
//   ZohPlant        x+ = Ad x + Bd u, y = C x: a continuous num(s)/den(s) (strictly proper) in
//                   controllable canonical form, balanced (Parlett-Reinsch, powers of two),
//                   Ad = e^{A h}, Bd = int_0^h e^{A r} dr B.
//   Converter       AD/DA above.
//   TrackingLoop    the loop above.
// A continuous filter is discretised by Tustin at h (core::tustin); PI/PID and phase lead are
// named forms of one: kp + ki/s + kd s/(tf s + 1), gain (s + zero)/(s + pole). A state space
// (A, B, C, D), continuous or discrete, becomes its transfer function: den = det(sI - A),
// num = det(sI - A + B C) - den + D den (characteristic polynomials by Faddeev-LeVerrier).
// The loop's linear dynamics (converters and noise left out), for reports and analysis:
//   response(w) = H(z) = F(z) C(z) P(z) / (1 + C(z) P(z)),  P(z) = C (zI - Ad)^-1 Bd,
//   z = e^{i w h}: command r to displacement x.
// As a LinearDynamics (core/linear_dynamics.h) the stage is what the integrator's loop sees: H
// then the load cell's d periods, H(z) z^-d, realised with the state [F's, C's, P's states,
// d registers]: v = F r, e = v - C x, u = C(e), x+ = Ad x + Bd u, output C x (no direct term),
// then the d-step register. Additive noise does not change it; converters make it kLinearised
// (their saturation and quantisation left out), else it is time-invariant.

#include <complex>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/delay.h"
#include "core/structure.h"

namespace rths::core {

class DiscreteFilter {
 public:
  DiscreteFilter();                                              // identity
  DiscreteFilter(std::vector<double> b, std::vector<double> a);  // @pre a[0] != 0, sizes >= 1
  double step(double x);
  void reset();
  std::complex<double> response(std::complex<double> z) const;  // b(z^-1) / a(z^-1)
  LinearBlock state_space() const { return direct_form_block(b_, a_); }

 private:
  std::vector<double> b_, a_, state_;
};

// The transfer function of a single-input single-output state space (A n x n, B and C n, D),
// both polynomials highest power first: den = det(sI - A), num = det(sI - A + B C) - den + D den
// (the SISO identity C adj(sI - A) B = det(sI - A + B C) - det(sI - A)). For a discrete state
// space the same polynomials are in z.
ContinuousTransferFunction state_space_transfer_function(const Mat& a, const Vec& b, const Vec& c,
                                                         double d);

class ZohPlant {
 public:
  // @pre deg numerator < deg denominator (highest power first), denominator[0] != 0, h > 0.
  ZohPlant(const std::vector<double>& numerator, const std::vector<double>& denominator, double h);
  double output() const { return c_.dot(x_); }
  void advance(double u);
  void reset() { x_.setZero(); }
  std::complex<double> response(std::complex<double> z) const;
  LinearBlock state_space() const;  // (Ad, Bd, C, 0)

 private:
  Mat ad_;
  Vec bd_, x_, next_;
  Eigen::RowVectorXd c_;
};

struct Converter {
  double range = 0.0, quantum = 0.0;         // m; 0 = none
  double analog_to_digital(double x) const;  // saturate, then quantise
  double digital_to_analog(double x) const;  // quantise, then saturate
};

// What a tracking loop holds besides its plant. An absent controller or feedforward is the
// identity; converter fields of 0 mean none.
struct TrackingLoopOptions {
  std::optional<DiscreteFilter> controller, feedforward;
  Converter converter;
  double displacement_noise_rms = 0.0;    // m, on the measured displacement
  double force_noise_rms = 0.0;           // N, on the measured force
  std::uint32_t force_delay_periods = 0;  // the force reading's lag in steps, 0..64
  std::uint64_t seed = 0;                 // of both noises
  std::string plant_name = "plant";       // in the block's label ("benchmark plant")
};

class TrackingLoop final : public DelayStage {
 public:
  static constexpr std::uint32_t kMaxForceDelayPeriods = 64;
  // Throws std::invalid_argument naming `field` for a bad converter, noise or force delay.
  TrackingLoop(ZohPlant plant, const TrackingLoopOptions& options, double h,
               const std::string& field);
  void reset() override;
  std::unique_ptr<DelayStage> clone() const override {
    return std::make_unique<TrackingLoop>(*this);
  }
  std::string describe() const override { return label_; }
  // -arg H(e^{i w h}) / w at w = 0.1 rad/s: the loop's low-frequency lag (s).
  double nominal_delay() const override { return nominal_delay_; }
  std::complex<double> response(double omega) const;  // H(e^{i omega h})
  double sensor_error() const override { return sensor_error_; }
  double measure_force(double force) override;
  Linearity linearity() const override;

 protected:
  double step_unscaled(const CommandSample& in) override;
  std::complex<double> unscaled_response(double omega) const override;  // H(z) z^-d
  LinearBlock unscaled_state_space() const override;

 private:
  std::string describe_loop(const TrackingLoopOptions& options) const;
  ZohPlant plant_;
  DiscreteFilter controller_, feedforward_;
  Converter converter_;
  double noise_rms_ = 0.0, h_ = 0.0, sensor_error_ = 0.0;
  double force_noise_rms_ = 0.0;
  std::vector<double> force_queue_;  // the last force_delay_periods + 1 readings, a ring
  std::size_t force_head_ = 0;
  std::uint64_t seed_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_;
  std::string label_;
  double nominal_delay_ = 0.0;
};

}  // namespace rths::core
