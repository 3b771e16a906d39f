#include "core/simulation.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/sparse_structure.h"

namespace rths::core {

void SimulationResult::truncate(std::size_t steps) {
  if (steps >= time.size()) return;
  const auto rows = static_cast<Eigen::Index>(steps);
  time.resize(steps);
  for (Mat* history : {&displacement, &velocity, &acceleration, &command, &realised,
                       &measured_force, &prediction_error}) {
    history->conservativeResize(rows, Eigen::NoChange);
  }
}

namespace {

void require_motion_at_dt(const HybridSetup& setup, const GroundMotion& motion_at_dt) {
  if (!(setup.dt > 0)) throw std::invalid_argument("simulation: dt must be > 0 s");
  if (std::abs(motion_at_dt.dt - setup.dt) > 1e-9 * setup.dt) {
    throw std::invalid_argument("simulation: ground motion '" + motion_at_dt.name + "' has dt " +
                                std::to_string(motion_at_dt.dt) + " s but the step is " +
                                std::to_string(setup.dt) + " s; resample it first");
  }
  if (motion_at_dt.acceleration.empty()) {
    throw std::invalid_argument("simulation: ground motion '" + motion_at_dt.name + "' is empty");
  }
}

// EXACT_ZOH integrates the numerical part exactly and holds the experimental force: K_x is the
// model's initial stiffness less the experimental parts' (the whole of it without any).
IntegratorParameters integrator_parameters(const HybridSetup& setup) {
  IntegratorParameters parameters;
  if (setup.integrator != IntegratorKind::kExactZoh) return parameters;
  const Mat experimental = setup.partition.experimental_stiffness();
  parameters.exact_stiffness = setup.model.stiffness;
  if (experimental.rows() == setup.model.stiffness.rows())
    parameters.exact_stiffness -= experimental;
  return parameters;
}

}  // namespace

void run_steps(const HybridSetup& setup, const GroundMotion& motion_at_dt,
               HybridEvaluator& restoring, StepHooks& hooks, const SimulationOptions& options,
               SimulationResult& result) {
  require_motion_at_dt(setup, motion_at_dt);
  auto integrator =
      make_integrator(setup.integrator, setup.model, setup.dt, integrator_parameters(setup));

  const int dofs = setup.model.dofs();
  const int actuators = restoring.actuators();
  const std::size_t steps = motion_at_dt.acceleration.size();
  const auto rows = static_cast<Eigen::Index>(steps);
  result = SimulationResult{};
  result.dt = setup.dt;
  result.time.assign(steps, 0.0);
  result.displacement = Mat::Zero(rows, dofs);
  result.velocity = Mat::Zero(rows, dofs);
  result.acceleration = Mat::Zero(rows, dofs);
  result.command = Mat::Zero(rows, actuators);
  result.realised = Mat::Zero(rows, actuators);
  result.measured_force = Mat::Zero(rows, actuators);
  result.prediction_error = Mat::Zero(rows, actuators);

  // Whatever stops the loop, the result keeps exactly the steps that completed.
  struct TruncateOnExit {
    SimulationResult& result;
    std::size_t completed = 1;
    ~TruncateOnExit() { result.truncate(completed); }
  } guard{result};

  const Vec mass_iota = mass_times(setup.model, setup.model.influence);
  Vec load = -mass_iota * motion_at_dt.acceleration[0];
  integrator->initialize(Vec::Zero(dofs), Vec::Zero(dofs), Vec::Zero(dofs), load);
  result.acceleration.row(0) = integrator->acceleration().transpose();
  if (!hooks.after_step(0, result)) return;

  for (std::size_t k = 1; k < steps; ++k) {
    hooks.before_step(k);
    const double t = static_cast<double>(k) * setup.dt;
    result.time[k] = t;
    load = -mass_iota * motion_at_dt.acceleration[k];
    restoring.set_time(t);
    integrator->step(load, restoring);
    const auto row = static_cast<Eigen::Index>(k);
    result.displacement.row(row) = integrator->displacement().transpose();
    result.velocity.row(row) = integrator->velocity().transpose();
    result.acceleration.row(row) = integrator->acceleration().transpose();
    result.command.row(row) = restoring.command().transpose();
    result.realised.row(row) = restoring.realised().transpose();
    result.measured_force.row(row) = restoring.measured_force().transpose();
    result.prediction_error.row(row) = restoring.prediction_error().transpose();
    guard.completed = k + 1;
    if (!restoring.hold().empty()) {
      result.held = restoring.hold();
      hooks.after_step(k, result);
      return;
    }
    const double peak = integrator->displacement().cwiseAbs().maxCoeff();
    if (!(peak <= options.divergence_bound)) {  // also catches NaN
      result.diverged = true;
      hooks.after_step(k, result);
      return;
    }
    if (!hooks.after_step(k, result)) return;
  }
}

SimulationResult simulate(const HybridSetup& setup, const GroundMotion& motion_at_dt,
                          const SimulationOptions& options, const AnswerSchedule& answers) {
  require_motion_at_dt(setup, motion_at_dt);
  check_stability(setup.integrator, max_omega(setup.model), setup.dt, setup.allow_unstable);

  HybridRestoring restoring(setup.partition, setup.delays, setup.dt, setup.servo_substeps,
                            setup.predictors);
  const bool replayed = !answers.actuator_used.empty() || !answers.storey_used.empty();
  const std::size_t steps = motion_at_dt.acceleration.size();
  if (replayed || !setup.links.empty()) {
    if (!is_explicit(setup.integrator))
      throw std::invalid_argument(to_string(setup.integrator) + " cannot use " +
                                  (replayed ? "a distributed run's answers" : "a case's link") +
                                  ": it iterates on the restoring force. Use an explicit "
                                  "integrator");
    restoring.replay_answers(replayed ? answers : link_schedule(setup.links, setup.dt, steps),
                             steps);
  }
  if (!is_explicit(setup.integrator) && !restoring.repeatable()) {
    throw std::invalid_argument(
        to_string(setup.integrator) +
        " cannot run with a delay stage: it iterates on the restoring force, which a delayed "
        "experimental substructure cannot repeat. Use an explicit integrator");
  }
  StepHooks no_hooks;
  SimulationResult result;
  run_steps(setup, motion_at_dt, restoring, no_hooks, options, result);
  return result;
}

}  // namespace rths::core
