#pragma once
// Effects of a physical rig that no linear actuator model holds, as delay stages
// (core/delay.h), so that an identified rig can be re-run as it was measured (identify/run) and
// a planned test can be tried against it.
//
// Input (CommandSample): t (s), u (m) from the stage before. Output: u_out (m). Initial state:
// at rest at u_out = 0. Equations, per step k:
//   backlash       play of total width w (m) between the drive and the specimen:
//                  u_out[k] = clamp(u_out[k-1], u[k] - w/2, u[k] + w/2).
//   velocity_limit a servo valve's flow limit, v_max (m/s) at step dt (s):
//                  u_out[k] = u_out[k-1] + clamp(u[k] - u_out[k-1], -v_max dt, v_max dt).
//   stroke_limit   the end of the actuator's stroke, s (m) either side of its centre:
//                  u_out[k] = clamp(u[k], -s, s).
//   SensorDrift    the displacement sensor and the load cell reading off the truth, the
//                  displacement sensor by a scale, both by an offset and a drift over time:
//                  u_out = u (the specimen is not moved); the displacement read =
//                  g u + d0 + d1 t (-, m, m/s) (sensor_error adds (g - 1) u + d0 + d1 t, so it
//                  reads the displacement this stage passes: place it after every stage that
//                  moves the specimen), the force the integrator receives = f + f0 + f1 t
//                  (N, N/s) (measure_force).
//   ViscousForce   a viscous force in parallel with the specimen (its own damping, a damper),
//                  which the load cell reads with the spring's: u_out = u (the motion passes
//                  unchanged), the force the integrator receives = f + c (u[k] - u[k-1]) / dt
//                  (c in N s/m, dt the stage's step in s) (measure_force).
//   InertiaForce   the specimen's own mass m (kg), moved with it, which the load cell reads with
//                  its restoring force: u_out = u, the force the integrator receives = f + m a[k],
//                  a[k] = (2 u[k] - 5 u[k-1] + 4 u[k-2] - u[k-3]) / dt^2, the backward
//                  difference exact for a cubic: the acceleration at step k itself (the central
//                  difference (u[k] - 2 u[k-1] + u[k-2]) / dt^2 is step k-1's, a lag of one step
//                  that an identification reads as a late load cell) (measure_force).
//   FrictionForce  a friction force beside the specimen (a bearing, a seal), read by the load
//                  cell: u_out = u, the force the integrator receives = f + F_c tanh(v[k] / v_s),
//                  v[k] = (3 u[k] - 4 u[k-1] + u[k-2]) / (2 dt), the backward difference exact for
//                  a parabola: the rate at step k itself (the first difference is step k - 1/2's,
//                  half a step late, which an identification reads as a late load cell) (F_c in N,
//                  v_s the smoothing velocity in m/s; Coulomb friction F_c sign(v) as v_s -> 0)
//                  (measure_force).
//   ForceDelay     the load cell's channel late by tau (s): u_out = u, the force the integrator
//                  receives = the force this stage was given at t - tau, interpolated linearly
//                  between its steps (the first step's before it) (measure_force).
// The identification's predictors (identify/model/model.cpp) apply the same recursions, so an
// identified width or limit re-runs as it was fitted; its specimen model (mass times the
// acceleration, friction_force tanh(v / smoothing_velocity), the force channel's delay) is the
// force stages' with the same parameters.
// Linear dynamics: a MotionLimit (backlash, velocity_limit, stroke_limit) is the identity once its
// non-linearity is left out (kLinearised: a small motion passes unchanged); SensorDrift is the
// identity, and so are ViscousForce, InertiaForce, FrictionForce and ForceDelay on the displacement
// they pass.
// Real-time safe: no allocation after construction.

#include <cmath>

#include "core/delay.h"

namespace rths::core {

// Backlash, VelocityLimit and StrokeLimit in one block (they differ only in the recursion): its
// state is the last output; its linear dynamics are the identity.
class MotionLimit final : public DelayStage {
 public:
  // @pre width >= 0 and finite (m) (throws std::invalid_argument).
  static MotionLimit backlash(double width);
  // @pre max_velocity > 0 and finite (m/s), dt > 0 (s) (throws std::invalid_argument).
  static MotionLimit velocity_limit(double max_velocity, double dt);
  // @pre stroke > 0 and finite (m) (throws std::invalid_argument).
  static MotionLimit stroke_limit(double stroke);
  void reset() override { output_ = 0.0; }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double nominal_delay() const override { return 0.0; }
  Linearity linearity() const override;

 protected:
  double step_unscaled(const CommandSample& in) override;
  std::optional<PlantModel> unscaled_transfer_function() const override { return PlantModel{}; }
  LinearBlock unscaled_state_space() const override { return gain_block(1.0); }

 private:
  enum class Kind { kBacklash, kVelocityLimit, kStrokeLimit };
  MotionLimit(Kind kind, double limit, double step);
  Kind kind_;
  double limit_;  // m, the backlash's width or the stroke; m/s, the velocity limit
  double reach_;  // m: half the width, the most the output moves in one step, or the stroke
  double output_ = 0.0;
};

struct SensorErrors {
  double displacement_offset = 0.0;  // m
  double displacement_drift = 0.0;   // m/s
  double force_offset = 0.0;         // N
  double force_drift = 0.0;          // N/s
  double displacement_scale = 1.0;   // -, multiplies the displacement read
};

// A stage that passes the motion unchanged and acts on what is read (SensorDrift and the force
// stages): no delay, no non-linearity, the identity as its linear dynamics. Each step it hands the
// sample it passes to observe(), where the stage keeps what its readings need.
class PassThroughStage : public DelayStage {
 public:
  double nominal_delay() const override { return 0.0; }
  Linearity linearity() const override { return {}; }

 protected:
  virtual void observe(const CommandSample& in) = 0;
  double step_unscaled(const CommandSample& in) final {
    observe(in);
    return in.displacement;
  }
  std::optional<PlantModel> unscaled_transfer_function() const final { return PlantModel{}; }
  LinearBlock unscaled_state_space() const final { return gain_block(1.0); }
};

class SensorDrift final : public PassThroughStage {
 public:
  // @pre every field finite (throws std::invalid_argument naming it).
  explicit SensorDrift(const SensorErrors& errors);
  void reset() override { time_ = passed_ = 0.0; }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double sensor_error() const override {
    return (errors_.displacement_scale - 1.0) * passed_ + errors_.displacement_offset +
           errors_.displacement_drift * time_;
  }
  double measure_force(double force) override {
    return force + errors_.force_offset + errors_.force_drift * time_;
  }

 protected:
  void observe(const CommandSample& in) override {
    time_ = in.time;
    passed_ = in.displacement;
  }

 private:
  SensorErrors errors_;
  double time_ = 0.0;    // s, of the last step
  double passed_ = 0.0;  // m, the displacement the last step passed
};

class ViscousForce final : public PassThroughStage {
 public:
  // @pre damping >= 0 and finite (N s/m), dt > 0 (s) (throws std::invalid_argument).
  ViscousForce(double damping, double dt);
  void reset() override { last_ = velocity_ = 0.0; }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double measure_force(double force) override { return force + damping_ * velocity_; }

 protected:
  void observe(const CommandSample& in) override {
    velocity_ = (in.displacement - last_) / dt_;
    last_ = in.displacement;
  }

 private:
  double damping_, dt_;
  double last_ = 0.0, velocity_ = 0.0;  // m, m/s: of the last step
};

class InertiaForce final : public PassThroughStage {
 public:
  // @pre mass >= 0 and finite (kg), dt > 0 (s) (throws std::invalid_argument).
  InertiaForce(double mass, double dt);
  void reset() override { u1_ = u2_ = u3_ = acceleration_ = 0.0; }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double measure_force(double force) override { return force + mass_ * acceleration_; }

 protected:
  void observe(const CommandSample& in) override {
    acceleration_ = (2.0 * in.displacement - 5.0 * u1_ + 4.0 * u2_ - u3_) / (dt_ * dt_);
    u3_ = u2_;
    u2_ = u1_;
    u1_ = in.displacement;
  }

 private:
  double mass_, dt_;
  double u1_ = 0.0, u2_ = 0.0, u3_ = 0.0;  // m: u[k-1], u[k-2], u[k-3]
  double acceleration_ = 0.0;              // m/s^2, of the last step
};

class FrictionForce final : public PassThroughStage {
 public:
  // @pre friction_force >= 0 and finite (N), smoothing_velocity > 0 and finite (m/s), dt > 0 (s)
  // (throws std::invalid_argument naming the field).
  FrictionForce(double friction_force, double smoothing_velocity, double dt);
  void reset() override { u1_ = u2_ = velocity_ = 0.0; }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double measure_force(double force) override {
    return force + friction_force_ * std::tanh(velocity_ / smoothing_velocity_);
  }

 protected:
  void observe(const CommandSample& in) override {
    velocity_ = (3.0 * in.displacement - 4.0 * u1_ + u2_) / (2.0 * dt_);
    u2_ = u1_;
    u1_ = in.displacement;
  }

 private:
  double friction_force_, smoothing_velocity_, dt_;
  double u1_ = 0.0, u2_ = 0.0;  // m: u[k-1], u[k-2]
  double velocity_ = 0.0;       // m/s, of the last step
};

class ForceDelay final : public PassThroughStage {
 public:
  // @pre delay >= 0 and finite (s), dt > 0 (s) (throws std::invalid_argument).
  ForceDelay(double delay, double dt);
  void reset() override {
    forces_.clear();
    time_ = 0.0;
  }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  // The displacement is not late (nominal_delay 0): the lag is on the force channel only.
  double measure_force(double force) override {
    forces_.push(time_, force);
    return forces_.at(time_ - delay_);
  }

 protected:
  void observe(const CommandSample& in) override { time_ = in.time; }

 private:
  double delay_;
  CommandHistory forces_;  // (t, force read) of the last steps
  double time_ = 0.0;      // s, of the last step
};

}  // namespace rths::core
