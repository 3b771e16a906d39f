#pragma once
// Restoring-force blocks: storey shear (N) as a function of inter-storey drift (m).
//
// Contract shared by every model (explicit state, Drake-style step):
//   trial(u)  -> {force, tangent}  evaluates at drift u from the last committed state; no mutation
//                                  of committed state (implicit integrators call it repeatedly).
//   commit()                        accepts the last trial as the new committed state.
//   step(u)   = trial(u) then commit(); what explicit integrators and actuators use.
// Initial state: zero drift, zero force. All models are rate-independent.

#include <memory>
#include <string>

namespace rths::core {

struct ForceState {
  double force = 0.0;    // N
  double tangent = 0.0;  // N/m, d force / d drift at the trial point
};

class RestoringForceModel {
 public:
  virtual ~RestoringForceModel() = default;
  virtual ForceState trial(double drift) = 0;
  virtual void commit() = 0;
  virtual void reset() = 0;  // back to the initial state
  virtual double initial_stiffness() const = 0;
  virtual std::unique_ptr<RestoringForceModel> clone() const = 0;
  virtual std::string describe() const = 0;

  double step(double drift) {
    const ForceState s = trial(drift);
    commit();
    return s.force;
  }
};

// f = k u.
class LinearSpring final : public RestoringForceModel {
 public:
  explicit LinearSpring(double stiffness);
  ForceState trial(double drift) override;
  void commit() override {}
  void reset() override {}
  double initial_stiffness() const override { return k_; }
  std::unique_ptr<RestoringForceModel> clone() const override;
  std::string describe() const override;

 private:
  double k_;
};

// What a hysteretic model keeps: its initial stiffness k0 (N/m) and, committed and trial, the
// drift (m) and one internal variable (the bilinear model's force in N, Bouc-Wen's z in m).
// commit() accepts the trial pair; reset() zeroes both.
class HystereticModel : public RestoringForceModel {
 public:
  void commit() override { committed_ = trial_; }
  void reset() override { committed_ = trial_ = {}; }
  double initial_stiffness() const override { return k0_; }
  // The model as r(u) = alpha k0 u + (1 - alpha) k0 uy z(u): its post-yield ratio alpha (-), its
  // yield drift uy (m) and, at rest, a model whose force is the dimensionless hysteretic
  // variable z (|z| <= 1; Bouc-Wen's z / uy, the bilinear's elastic-perfectly-plastic drift /
  // uy). (1 - alpha) k0 uy is then the hysteretic force, as rths identify's F_bw.
  struct Parts {
    double linear_ratio = 0.0, yield_drift = 0.0;
    std::unique_ptr<RestoringForceModel> unit_hysteresis;
  };
  virtual Parts parts() const = 0;

 protected:
  explicit HystereticModel(double k0) : k0_(k0) {}
  struct State {
    double drift = 0.0, internal = 0.0;
  };
  double k0_;
  State committed_, trial_;
};

// Bilinear with kinematic hardening. Elastic stiffness k0, yield force fy = k0 * uy, post-yield
// stiffness b * k0. The force stays within the band  b k0 u +/- (1 - b) fy  (return mapping), so
// b < 1 is a softening response. @pre k0 > 0, uy > 0, 0 <= b <= 1. Internal variable: the force.
class BilinearKinematic final : public HystereticModel {
 public:
  BilinearKinematic(double k0, double yield_drift, double post_yield_ratio);
  ForceState trial(double drift) override;
  std::unique_ptr<RestoringForceModel> clone() const override;
  std::string describe() const override;
  Parts parts() const override;

 private:
  double fy_, b_;
};

// Bouc–Wen: f = alpha k0 u + (1 - alpha) k0 z, with the hysteretic drift z (m) obeying
//   dz/du = A - |z|^n (beta sgn(du z) + gamma),  A = 1,  beta + gamma = 1 / uy^n,
// so z saturates at uy. `beta_fraction` = beta uy^n (0.5 gives the classic beta = gamma).
// z is integrated over each drift increment with RK4 sub-steps of at most uy / 50. Internal
// variable: z.
class BoucWen final : public HystereticModel {
 public:
  BoucWen(double k0, double yield_drift, double alpha, double n, double beta_fraction);
  ForceState trial(double drift) override;
  std::unique_ptr<RestoringForceModel> clone() const override;
  std::string describe() const override;
  Parts parts() const override;

 private:
  double dz_du(double z, double du) const;
  double uy_, alpha_, n_, beta_, gamma_;
};

// A specimen with inertia and damping, as a force transducer between actuator and specimen
// measures it: f = m x'' + c x' + r(x), r the wrapped model, x' = (x - x1) / h and
// x'' = (x - 2 x1 + x2) / h^2 the backward differences over the committed drifts x1, x2 of the
// previous two calls (h s apart: the servo period). Tangent d f / d x = r' + c / h + m / h^2.
// @pre m >= 0, c >= 0, h > 0, a model.
class InertialSpecimen final : public RestoringForceModel {
 public:
  InertialSpecimen(std::unique_ptr<RestoringForceModel> model, double mass, double damping,
                   double period);
  InertialSpecimen(const InertialSpecimen& other);
  ForceState trial(double drift) override;
  void commit() override;
  void reset() override;
  double initial_stiffness() const override { return model_->initial_stiffness(); }
  std::unique_ptr<RestoringForceModel> clone() const override;
  std::string describe() const override;
  // r, m (kg) and c (N s/m) apart: a force predictor takes r as its shape and c as its damping
  // (core/force_predictor.h), since its rates come from the integrator, not from calls h apart.
  const RestoringForceModel& restoring() const { return *model_; }
  double mass() const { return m_; }
  double damping() const { return c_; }

 private:
  std::unique_ptr<RestoringForceModel> model_;
  double m_, c_, h_;
  double x1_ = 0.0, x2_ = 0.0, trial_ = 0.0;
};

}  // namespace rths::core
