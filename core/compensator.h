#pragma once
// The interface every delay compensator implements (the blocks are in core/compensation.h): a
// block that shapes the command sent to an actuator from the target the integrator computed and
// the displacement the actuator realised.
//
// Input  (CompensatorInput): t (s), the target x_t (m) and x_m (m, the displacement realised one
//        step earlier, as the sensor read it).
// Output: the command u_c (m) given to the actuator's delay chain (core/delay.h).
// Contract for the loop thread: step() allocates nothing and never blocks; reset() returns the
// block to rest. Linear dynamics (core/linear_dynamics.h), from x_t to u_c, where the block
// states them; otherwise kNone naming the block, and frequency_response / state_space throw
// std::invalid_argument.

#include <complex>
#include <memory>
#include <string>

#include "core/linear_dynamics.h"

namespace rths::core {

struct CompensatorInput {
  double time = 0.0;      // s
  double target = 0.0;    // m, x_t: what the integrator wants realised
  double measured = 0.0;  // m, x_m: what the sensor read of the previous step's displacement
};

class Compensator : public LinearDynamics {
 public:
  // Returns the command u_c (m). Real-time safe.
  virtual double step(const CompensatorInput& in) = 0;
  virtual void reset() = 0;
  virtual std::unique_ptr<Compensator> clone() const = 0;
  virtual std::string describe() const = 0;
  // Low-frequency phase lead the block adds (s), for reports; 0 for ATS (it adapts).
  virtual double nominal_lead() const = 0;
  // By default not representable (kNone, naming the block); both others then throw.
  Linearity linearity() const override;
  std::complex<double> frequency_response(double omega) const override;
  LinearBlock state_space() const override;
};

}  // namespace rths::core
