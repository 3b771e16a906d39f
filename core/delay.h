#pragma once
// Delay and actuator blocks, in simulated time: what happens between the displacement the
// integrator computes (u_comp) and the one the specimen actually sees (u_real).
//
// Input  (CommandSample): t (s), u_comp (m), v_comp (m/s, the integrator's computed velocity).
// Output: u_real (m).
// Every stage is called once per step with strictly increasing t (spacing dt, the integration
// step) and is deterministic given its seed, so an in-process run and a distributed lockstep run
// agree bit for bit. Initial state: at rest, u_real = 0 before any command.
//
// Equations (tau = delay):
//   TimeShift       u_real(t) = u_comp(t - tau), linear interpolation on the command history;
//                   tau need not be a multiple of dt; before t = tau the first command is held.
//   Eq1Lead         u_real = u_comp + v_comp tau   -- the source paper's Eq. 1 exactly as printed.
//                   With tau > 0 this is a LEAD (overshoot), which adds damping.
//   Eq1Lag          u_real = u_comp - v_comp tau   -- the first-order Taylor form of a true lag.
//   FirstOrder      T du_real/dt = u_comp - u_real, discretised exactly for a command held over
//                   the step: u_real[k] = e^(-dt/T) u_real[k-1] + (1 - e^(-dt/T)) u_comp[k].
//                   Its phase lag at low frequency is about T.
//   TransferFunction G(s) = N(s)/D(s), bilinear (Tustin) discretised, direct form II transposed.
//   BenchmarkActuator the nominal actuator + control-structure-interaction plant of the RTHS
//                   benchmark (Silva, Dyke et al. 2020), as a TransferFunction.
//   Jitter          TimeShift whose delay is redrawn each step: tau_k = max(0, mean + sd N(0,1)),
//                   capped at mean + 6 sd; std::mt19937_64 with the given seed.
//   Trace           TimeShift whose delay follows a recorded trace tau(t) (linear interpolation,
//                   held at the ends).
// Every stage also carries an amplitude gain g: its output is g * (the above).
//
// Linear dynamics (core/linear_dynamics.h), the gain g included, from the command u_comp to what
// the loop feeds back (u_real; a stage that delays the load cell's force by d steps adds z^-d,
// as the force of a linear specimen is its stiffness times u_real):
//   NoDelay           H = 1.
//   TimeShift         H = e^{-i w tau}; realised as the interpolated register above.
//   FirstOrder        H = 1 / (1 + i w T); realised as x+ = e x + (1 - e) u,
//                     y = e x + (1 - e) u, e = e^(-dt/T) (the recursion above).
//   TransferFunction  H = N(i w) / D(i w); realised as its direct form II transposed.
//   TrackingLoop      core/tracking.h.
//   Eq1Lead, Eq1Lag   none: they read the command's velocity, which a single-input block has not.
//   Jitter, Trace     none: their delay changes with time.

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/linear_dynamics.h"

namespace rths::core {

struct CommandSample {
  double time = 0.0;          // s
  double displacement = 0.0;  // m
  double velocity = 0.0;      // m/s
};

class DelayStage : public LinearDynamics {
 public:
  // Real-time safe: no allocation after construction.
  double step(const CommandSample& in) { return gain_ * step_unscaled(in); }
  virtual void reset() = 0;
  virtual std::unique_ptr<DelayStage> clone() const = 0;
  virtual std::string describe() const = 0;
  // The lag this stage nominally adds at low frequency (s); negative for a lead. For reports.
  virtual double nominal_delay() const = 0;
  // A stage that models the displacement sensor: its error on the last step's reading (m), which
  // the reading adds to the stage's output. 0 for a stage without a sensor.
  virtual double sensor_error() const { return 0.0; }
  // A stage that models the load cell: the force (N) the integrator receives in this servo
  // period when the specimen's force is `force` (noise, transport delay). Called once per step
  // after step(). Identity for a stage without one. Real-time safe.
  virtual double measure_force(double force) { return force; }

  void set_gain(double gain) { gain_ = gain; }
  double gain() const { return gain_; }

  // The stage's linear dynamics, the gain included (equations above). By default a stage is not
  // representable (kNone, naming it); a linear stage overrides linearity() and the unscaled_*.
  Linearity linearity() const override;
  std::complex<double> frequency_response(double omega) const final;
  LinearBlock state_space() const final;
  std::optional<PlantModel> transfer_function() const final;

 protected:
  virtual double step_unscaled(const CommandSample& in) = 0;
  // Without the gain. The response defaults to the transfer function's, when there is one.
  virtual std::optional<PlantModel> unscaled_transfer_function() const { return std::nullopt; }
  virtual std::complex<double> unscaled_response(double omega) const;
  virtual LinearBlock unscaled_state_space() const;
  // Throws std::invalid_argument with linearity().note when the stage is not representable.
  void require_analysable() const;

 private:
  double gain_ = 1.0;
};

class NoDelay final : public DelayStage {
 public:
  void reset() override {}
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override { return "none"; }
  double nominal_delay() const override { return 0.0; }
  Linearity linearity() const override { return {}; }

 protected:
  double step_unscaled(const CommandSample& in) override { return in.displacement; }
  std::optional<PlantModel> unscaled_transfer_function() const override { return PlantModel{}; }
  LinearBlock unscaled_state_space() const override { return gain_block(1.0); }
};

// History of (t, u) samples in a fixed ring, with u(t_query) by linear interpolation.
class CommandHistory {
 public:
  // Keeps enough samples to look back `max_lookback` seconds at step `dt`.
  CommandHistory(double max_lookback, double dt);
  void push(double time, double value);
  // @pre at least one sample pushed. Before the oldest kept sample: that sample's value.
  double at(double time) const;
  void clear();

 private:
  std::vector<double> times_, values_;
  std::size_t head_ = 0, size_ = 0;
};

class TimeShift final : public DelayStage {
 public:
  TimeShift(double delay, double dt);  // @pre delay >= 0, dt > 0
  void reset() override { history_.clear(); }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double nominal_delay() const override { return delay_; }
  Linearity linearity() const override { return {}; }

 protected:
  double step_unscaled(const CommandSample& in) override;
  std::optional<PlantModel> unscaled_transfer_function() const override;
  LinearBlock unscaled_state_space() const override { return shift_block(delay_, dt_); }

 private:
  double delay_, dt_;
  CommandHistory history_;
};

class Eq1Lead final : public DelayStage {
 public:
  explicit Eq1Lead(double delay) : delay_(delay) {}
  void reset() override {}
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double nominal_delay() const override { return -delay_; }
  Linearity linearity() const override;

 protected:
  double step_unscaled(const CommandSample& in) override {
    return in.displacement + in.velocity * delay_;
  }

 private:
  double delay_;
};

class Eq1Lag final : public DelayStage {
 public:
  explicit Eq1Lag(double delay) : delay_(delay) {}
  void reset() override {}
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double nominal_delay() const override { return delay_; }
  Linearity linearity() const override;

 protected:
  double step_unscaled(const CommandSample& in) override {
    return in.displacement - in.velocity * delay_;
  }

 private:
  double delay_;
};

class FirstOrderActuator final : public DelayStage {
 public:
  FirstOrderActuator(double time_constant, double dt);  // @pre time_constant > 0, dt > 0
  void reset() override { state_ = 0.0; }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double nominal_delay() const override { return time_constant_; }
  Linearity linearity() const override { return {}; }

 protected:
  double step_unscaled(const CommandSample& in) override;
  std::optional<PlantModel> unscaled_transfer_function() const override;
  LinearBlock unscaled_state_space() const override;

 private:
  double time_constant_, decay_, state_ = 0.0;
};

class TransferFunctionStage final : public DelayStage {
 public:
  // Continuous-time coefficients, highest power of s first. @pre proper (deg num <= deg den),
  // denominator leading coefficient non-zero, dt > 0.
  TransferFunctionStage(std::vector<double> numerator, std::vector<double> denominator, double dt,
                        std::string label = "transfer-function");
  void reset() override;
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override { return label_; }
  // -d(phase)/d(omega) at omega -> 0 of the continuous G(s), i.e. its low-frequency group delay.
  double nominal_delay() const override { return group_delay_; }
  double dc_gain() const { return dc_gain_; }
  // The discrete filter: b (numerator) and a (denominator, a[0] = 1) in powers of z^-1.
  const std::vector<double>& discrete_numerator() const { return b_; }
  const std::vector<double>& discrete_denominator() const { return a_; }
  Linearity linearity() const override { return {}; }

 protected:
  double step_unscaled(const CommandSample& in) override;
  std::optional<PlantModel> unscaled_transfer_function() const override;
  LinearBlock unscaled_state_space() const override { return direct_form_block(b_, a_); }

 private:
  std::vector<double> numerator_, denominator_;  // continuous, highest power first
  std::vector<double> b_, a_;                    // discrete, a_[0] == 1
  std::vector<double> state_;
  std::string label_;
  double group_delay_ = 0.0, dc_gain_ = 1.0;
};

// The benchmark's nominal plant from command to measured actuator displacement:
//   Gp(s) = a1b0 / ((s^2 + b1 s + b2) ((s + a3)(me s^2 + ce s + ke) + a2 s) + a1b0),
//   a1b0 = 2.13e13, a2 = 4.23e6, a3 = 3.3, b1 = 425, b2 = 1e5, me = 29.1 kg, ce = 114.6 N s/m,
//   ke = 1.19e6 N/m. DC gain 0.982, low-frequency group delay 25.1 ms (both derived in delay.cpp
//   and tested). Source: the benchmark's public MATLAB set-up as reused in
//   DanielMaurelE/vRTHS_AMBC_MRdamper; not checked against the paper's PDF (see delay.cpp).
std::unique_ptr<TransferFunctionStage> make_benchmark_actuator(double dt);
// The same plant as continuous polynomials (highest power of s first), for model-based design.
struct ContinuousTransferFunction {
  std::vector<double> numerator, denominator;
};
ContinuousTransferFunction benchmark_actuator_transfer_function();
// The plant with every parameter given (the defaults are the nominal values above, gain 1):
//   gain a1b0 / ((s^2 + beta1 s + beta2) ((s + a3)(m s^2 + c s + k) + a2 s) + a1b0).
struct BenchmarkPlantParameters {
  double a1_beta0 = 2.13e13, a2 = 4.23e6, a3 = 3.3, beta1 = 425.0, beta2 = 1e5, gain = 1.0;
  double mass = 29.1, damping = 114.6, stiffness = 1.19e6;  // kg, N s/m, N/m
};
ContinuousTransferFunction benchmark_actuator_transfer_function(const BenchmarkPlantParameters& p);

// Tustin map of num(s)/den(s) (highest power of s first, proper) at step dt: b and a in ascending
// powers of z^-1, a[0] = 1. Throws std::invalid_argument when improper, empty, or D(2/dt) = 0.
struct DiscreteCoefficients {
  std::vector<double> b, a;
};
DiscreteCoefficients tustin(const std::vector<double>& numerator,
                            const std::vector<double>& denominator, double dt);

class JitterShift final : public DelayStage {
 public:
  JitterShift(double mean_delay, double std_dev, std::uint64_t seed, double dt);
  void reset() override;
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double nominal_delay() const override { return mean_; }
  double last_delay() const { return last_delay_; }
  Linearity linearity() const override;

 protected:
  double step_unscaled(const CommandSample& in) override;

 private:
  double mean_, std_dev_, cap_;
  std::uint64_t seed_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  CommandHistory history_;
  double last_delay_ = 0.0;
};

struct DelayTrace {
  std::vector<double> time;   // s, increasing
  std::vector<double> delay;  // s, >= 0
  double at(double t) const;
  double max() const;
};

class TraceShift final : public DelayStage {
 public:
  TraceShift(DelayTrace trace, double dt);
  void reset() override { history_.clear(); }
  std::unique_ptr<DelayStage> clone() const override;
  std::string describe() const override;
  double nominal_delay() const override;
  Linearity linearity() const override;

 protected:
  double step_unscaled(const CommandSample& in) override;

 private:
  DelayTrace trace_;
  CommandHistory history_;
};

class Compensator;  // core/compensator.h

// Stages applied in order; the command's velocity is passed unchanged to every stage.
// step() returns the specimen's displacement; measured() what the displacement sensor read at
// that step (the output plus every stage's sensor_error()); measure_force() passes the
// specimen's force through every stage's load cell, in order.
// An optional compensator (core/compensation.h) shapes the command before the first stage; it
// sees the target (the command given to step) and the measured displacement of the previous
// step, and nothing else in the chain changes.
// Linear dynamics: the compensator C (if any), then the stages G_1 .. G_n in order:
//   H = (G_1 .. G_n)(i w) C(i w), the stages with a transfer function folded into one
//   g e^{-s tau} N(s) / D(s) and evaluated once, the others multiplied in;
//   state space series(C, series(.. series(1, G_1) .., G_n)).
// Its linearity is the least of its blocks' (kNone before kLinearised before kFrozen), the notes
// naming each block, joined by "; ".
class DelayChain final : public LinearDynamics {
 public:
  DelayChain();
  ~DelayChain() override;
  DelayChain(const DelayChain& other);
  DelayChain& operator=(const DelayChain& other);
  DelayChain(DelayChain&&) noexcept;
  DelayChain& operator=(DelayChain&&) noexcept;

  void add(std::unique_ptr<DelayStage> stage) { stages_.push_back(std::move(stage)); }
  void set_compensator(std::unique_ptr<Compensator> compensator);
  const Compensator* compensator() const { return compensator_.get(); }
  double step(const CommandSample& in);
  double measured() const { return measured_; }
  double measure_force(double force);
  void reset();
  // The stages' lag minus the compensator's nominal lead (s).
  double nominal_delay() const;
  std::string describe() const;
  bool empty() const { return stages_.empty() && !compensator_; }
  Linearity linearity() const override;
  std::complex<double> frequency_response(double omega) const override;
  LinearBlock state_space() const override;

 private:
  std::vector<std::unique_ptr<DelayStage>> stages_;
  std::unique_ptr<Compensator> compensator_;
  double measured_ = 0.0;  // m, what the sensor read at the previous step
};

}  // namespace rths::core
