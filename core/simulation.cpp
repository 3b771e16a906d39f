#include "core/simulation.h"

#include <algorithm>
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
  for (std::vector<double>* series : {&peak_displacement, &peak_velocity, &base_shear})
    if (series->size() > steps) series->resize(steps);
  for (std::vector<int>* series : {&peak_displacement_dof, &peak_velocity_dof})
    if (series->size() > steps) series->resize(steps);
}

Eigen::Index SimulationResult::column_of_dof(int dof) const {
  if (dofs.empty()) return dof >= 0 && dof < displacement.cols() ? dof : -1;
  const auto at = std::lower_bound(dofs.begin(), dofs.end(), dof);
  return at != dofs.end() && *at == dof ? at - dofs.begin() : -1;
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

void require_kept_dofs(const std::vector<int>& kept, int dofs) {
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (kept[i] < 0 || kept[i] >= dofs)
      throw std::invalid_argument("simulation: kept DOF " + std::to_string(kept[i] + 1) +
                                  " is outside the model's 1.." + std::to_string(dofs));
    if (i > 0 && kept[i] <= kept[i - 1])
      throw std::invalid_argument("simulation: kept DOFs must be ascending and unique");
  }
}

// A fresh result with every history sized for `steps` rows: u, v, a for the kept DOFs (every DOF when
// options.kept_dofs is empty), the actuators', the per-step peaks and the base shear if asked.
void size_result(SimulationResult& result, const HybridSetup& setup, std::size_t steps,
                 int actuators, const SimulationOptions& options) {
  const int dofs = setup.model.dofs();
  require_kept_dofs(options.kept_dofs, dofs);
  result = SimulationResult{};
  result.dt = setup.dt;
  const auto rows = static_cast<Eigen::Index>(steps);
  const auto kept = options.kept_dofs.empty() ? dofs : static_cast<int>(options.kept_dofs.size());
  result.dofs = options.kept_dofs;
  result.time.assign(steps, 0.0);
  result.displacement = Mat::Zero(rows, kept);
  result.velocity = Mat::Zero(rows, kept);
  result.acceleration = Mat::Zero(rows, kept);
  result.command = Mat::Zero(rows, actuators);
  result.realised = Mat::Zero(rows, actuators);
  result.measured_force = Mat::Zero(rows, actuators);
  result.prediction_error = Mat::Zero(rows, actuators);
  if (options.peaks) {
    result.peak_displacement.assign(steps, 0.0);
    result.peak_velocity.assign(steps, 0.0);
    result.peak_displacement_dof.assign(steps, 0);
    result.peak_velocity_dof.assign(steps, 0);
  }
  if (options.base_shear) result.base_shear.assign(steps, 0.0);
}

// The base shear's terms: M iota (kg per DOF) and iota^T M iota (kg).
struct ShearTerms {
  Vec mass_iota;
  double iota_mass_iota = 0.0;
};

// Row `k` of the kept DOFs' u, v and a, the step's peaks over every DOF, and the base shear
// (N, iota^T M a + iota^T M iota a_g) when the result keeps it.
void store_state(SimulationResult& result, std::size_t k, const Integrator& integrator,
                 const ShearTerms& shear, double ground_acceleration) {
  const Vec &u = integrator.displacement(), &v = integrator.velocity(),
            &a = integrator.acceleration();
  if (!result.base_shear.empty())
    result.base_shear[k] = shear.mass_iota.dot(a) + shear.iota_mass_iota * ground_acceleration;
  const auto row = static_cast<Eigen::Index>(k);
  if (result.dofs.empty()) {
    result.displacement.row(row) = u.transpose();
    result.velocity.row(row) = v.transpose();
    result.acceleration.row(row) = a.transpose();
  } else {
    for (std::size_t c = 0; c < result.dofs.size(); ++c) {
      const auto column = static_cast<Eigen::Index>(c);
      const Eigen::Index dof = result.dofs[c];
      result.displacement(row, column) = u[dof];
      result.velocity(row, column) = v[dof];
      result.acceleration(row, column) = a[dof];
    }
  }
  if (result.peak_displacement.empty()) return;
  Eigen::Index at = 0;
  result.peak_displacement[k] = u.size() > 0 ? u.cwiseAbs().maxCoeff(&at) : 0.0;
  result.peak_displacement_dof[k] = static_cast<int>(at);
  result.peak_velocity[k] = v.size() > 0 ? v.cwiseAbs().maxCoeff(&at) : 0.0;
  result.peak_velocity_dof[k] = static_cast<int>(at);
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
  const std::size_t steps = motion_at_dt.acceleration.size();
  size_result(result, setup, steps, restoring.actuators(), options);

  // Whatever stops the loop, the result keeps exactly the steps that completed.
  struct TruncateOnExit {
    SimulationResult& result;
    std::size_t completed = 1;
    ~TruncateOnExit() { result.truncate(completed); }
  } guard{result};

  ShearTerms shear{mass_times(setup.model, setup.model.influence), 0.0};
  const Vec& mass_iota = shear.mass_iota;
  shear.iota_mass_iota = setup.model.influence.dot(mass_iota);
  Vec load = -mass_iota * motion_at_dt.acceleration[0];
  integrator->initialize(Vec::Zero(dofs), Vec::Zero(dofs), Vec::Zero(dofs), load);
  store_state(result, 0, *integrator, shear, motion_at_dt.acceleration[0]);
  if (!hooks.after_step(0, result)) return;

  for (std::size_t k = 1; k < steps; ++k) {
    hooks.before_step(k);
    const double t = static_cast<double>(k) * setup.dt;
    result.time[k] = t;
    load = -mass_iota * motion_at_dt.acceleration[k];
    restoring.set_time(t);
    integrator->step(load, restoring);
    const auto row = static_cast<Eigen::Index>(k);
    store_state(result, k, *integrator, shear, motion_at_dt.acceleration[k]);
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
    const double peak = options.peaks ? result.peak_displacement[k]
                                      : integrator->displacement().cwiseAbs().maxCoeff();
    if (!(peak <= options.divergence_bound)) {  // also catches NaN
      result.diverged = true;
      hooks.after_step(k, result);
      return;
    }
    if (!hooks.after_step(k, result)) return;
  }
}

SimulationResult simulate(const HybridSetup& setup, const GroundMotion& motion_at_dt,
                          const SimulationOptions& options, const AnswerSchedule& answers,
                          StepHooks* hooks) {
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
  run_steps(setup, motion_at_dt, restoring, hooks ? *hooks : no_hooks, options, result);
  const PredictorSet& predictors = restoring.predictors();
  if (!predictors.empty())
    for (std::size_t a = 0; a < setup.partition.actuator_storeys.size(); ++a)
      result.predictor_models.push_back(predictors.has(a) ? predictors.at(a).model_text() : "");
  return result;
}

}  // namespace rths::core
