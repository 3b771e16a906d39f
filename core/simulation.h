#pragma once
// In-process hybrid simulation: structure + integrator + numerical storeys + delayed experimental
// storeys under a ground motion. The reference run is the same setup with no delay stages.
//
// Input: a ground motion already at the integration step dt (m/s^2).
// Output: histories at t_k = k dt, k = 0..N (N = number of motion samples), SI units.

#include <string>
#include <vector>

#include "core/ground_motion.h"
#include "core/integrators.h"
#include "core/substructure.h"

namespace rths::core {

struct HybridSetup {
  StructuralModel model;
  IntegratorKind integrator = IntegratorKind::kExplicitNewmark;
  double dt = 0.0;  // s
  bool allow_unstable = false;
  HybridPartition partition;
  std::vector<DelayChain> delays;  // one per actuator (partition.actuator_storeys); may be empty
};

struct SimulationResult {
  double dt = 0.0;
  std::vector<double> time;                  // s
  Mat displacement;                          // m, rows = steps, cols = DOFs (relative to ground)
  Mat velocity;                              // m/s
  Mat acceleration;                          // m/s^2 (relative)
  Mat command, realised, measured_force;     // per actuator: m, m, N
  bool diverged = false;                     // stopped early: |u| exceeded the divergence bound
  std::size_t steps() const { return time.size(); }
  // Keeps the first `steps` rows of every history (a run that stopped early).
  void truncate(std::size_t steps);
};

struct SimulationOptions {
  // Stop, marking the result diverged, when any |u| exceeds this (m). Protects sweeps from
  // unstable cases running to inf/NaN.
  double divergence_bound = 1.0e3;
};

// Throws std::invalid_argument when dt is beyond the integrator's limit (unless allowed), when
// the motion's dt differs from setup.dt, or when an implicit integrator meets a delay stage.
SimulationResult simulate(const HybridSetup& setup, const GroundMotion& motion_at_dt,
                          const SimulationOptions& options = {});

}  // namespace rths::core
