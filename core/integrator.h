#pragma once
// The integrator interface: what every time-stepping scheme of core/integrators.h (and the exact
// zero-order-hold one, core/exact_zoh.h) offers the stepping loop, and what it asks of the
// structure each step. Units SI: displacement m, velocity m/s, force N, time s.

#include <memory>

#include "core/structure.h"

namespace rths::core {

enum class IntegratorKind {
  kExplicitNewmark,
  kCentralDifference,
  kChenRicles,
  kNewmarkAverageAcceleration,
  kAlphaOS,
  kKRAlpha,
  kExactZoh
};

// Parameters of the dissipative schemes (defaults: no numerical dissipation).
struct IntegratorParameters {
  double alpha_os = 1.0;      // ALPHA_OS alpha, in [2/3, 1]
  double rho_infinity = 1.0;  // KR_ALPHA spectral radius at infinite frequency, in [0, 1]
  // EXACT_ZOH: the linear stiffness integrated exactly (N/m, n x n; a hybrid run's numerical
  // part K - K_e); empty: the model's whole stiffness.
  Mat exact_stiffness;
};

// What an integrator asks of the structure each step.
class RestoringEvaluator {
 public:
  virtual ~RestoringEvaluator() = default;
  // Restoring force at trial displacement u (m) and velocity v (m/s); `tangent` may be null and is
  // only requested by implicit integrators. Must not mutate committed state.
  virtual const Vec& trial(const Vec& u, const Vec& v, Mat* tangent) = 0;
  // The last trial is accepted for this step.
  virtual void commit() = 0;
  // Whether trial() may be called more than once per step (false for a delayed or remote
  // experimental substructure, whose measurement cannot be repeated).
  virtual bool repeatable() const = 0;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  // Sets u0, v0 and a0 from equilibrium M a0 = p0 - C v0 - r(u0).
  virtual void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) = 0;
  // Advances one step under load p_{k+1}. Real-time safe after initialize() for the explicit
  // integrators (no allocation).
  virtual void step(const Vec& load_next, RestoringEvaluator& restoring) = 0;

  const Vec& displacement() const { return u_; }
  const Vec& velocity() const { return v_; }
  const Vec& acceleration() const { return a_; }
  double dt() const { return dt_; }
  virtual IntegratorKind kind() const = 0;

 protected:
  // keep_dense = false: m_, c_ and k0_ stay empty (an explicit scheme keeps its own algebra).
  Integrator(const StructuralModel& model, double dt, bool keep_dense = true);
  Mat m_, c_, k0_;
  double dt_;
  Vec u_, v_, a_;
};

}  // namespace rths::core
