#pragma once
// Substructuring of a structure into a numerical part (in the coordinator or a substructure node)
// and an experimental part (specimens behind actuators). A shear building is split by storeys;
// a structure given by matrices by DOFs: its "storeys" are then its DOFs (B = I), each
// experimental DOF's specimen acts between that DOF and the ground, and the numerical part is the
// linear K_N = K - K_e as a matrix (plus no per-DOF model). An experimental element between DOFs
// (a storey's damper or brace, OpenFresco's twoNodeLink) adds a row b_e to B after the n DOF rows:
// its deformation is x_e = b_e . u (u_j - u_i for a storey, cos(theta) (u_j - u_i) for a brace at
// theta, any influence row) and its force f_e enters every DOF by the same row, r += b_e f_e.
// "Storeys" are thus channels: n DOFs (or storeys), then the elements, one actuator each.
//
// Blocks:
//   StoreyAssembly            drifts d = B u  and DOF forces r = B^T V  (shear building B:
//                             d_i = u_i - u_{i-1}; by DOFs B = [I; b_1; ...; b_m]).
//   NumericalSubstructure     input storey drifts (m) -> storey shears (N); trial/commit.
//   Actuator                  input CommandSample (commanded drift) -> {realised drift, measured
//                             force}: delay chain, then the specimen's restoring-force model.
//   HybridRestoring           RestoringEvaluator for in-process runs: numerical + actuators.
// Storey shear V_s = V_numerical_s + V_experimental_s, summed in that order everywhere
// (in-process and distributed) so results agree bit for bit.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/answer_replay.h"
#include "core/delay.h"
#include "core/force_predictor.h"
#include "core/integrators.h"
#include "core/restoring_force.h"
#include "core/structure.h"

namespace rths::core {

// Makes a storey model of initial stiffness k (N/m).
using StoreyModelFactory = std::function<std::unique_ptr<RestoringForceModel>(double k)>;
StoreyModelFactory linear_factory();

class StoreyAssembly;

// An experimental element's deformation x = sum over terms of coefficient * u[dof] (m; dof
// 0-based): {{j, 1}, {i, -1}} for the storey between DOFs i and j.
struct ElementRow {
  std::vector<std::pair<int, double>> terms;
  // "DOF 2 - DOF 1", "0.866 (DOF 3 - DOF 1)" or the row's terms, 1-based.
  std::string describe() const;
};

using RowSparseMat = Eigen::SparseMatrix<double, Eigen::RowMajor>;

struct HybridPartition {
  // One entry per storey; null where that storey has no numerical / experimental part.
  std::vector<std::unique_ptr<RestoringForceModel>> numerical;
  std::vector<std::unique_ptr<RestoringForceModel>> experimental;
  // Storeys (0-based) that carry an experimental part: one actuator each, in this order.
  std::vector<int> actuator_storeys;
  // Split by DOFs (a structure given by matrices): B = I and the numerical part's linear
  // stiffness K_N (N/m, n x n) acting on the DOF displacements; empty for a shear building.
  // Sparse (row-major, only its nonzeros stored): a large model's K_N is O(nnz) to hold and to
  // apply; a condensed model's is as full as before, and applied in the same sums.
  bool by_dofs = false;
  RowSparseMat numerical_matrix;
  // By DOFs: the experimental elements between DOFs, channel n + e each (after the n DOFs).
  std::vector<ElementRow> elements;

  // Channels (storeys or DOFs, then elements) and DOFs of the structure.
  int channels() const { return static_cast<int>(numerical.size()); }
  int dofs() const { return channels() - static_cast<int>(elements.size()); }
  // "storey 2", "DOF 2" or "element 1 (DOF 2 - DOF 1)" for channel s (0-based).
  std::string channel_name(int s) const;

  // Whether storey (or DOF) s has a numerical part: a model, or a non-zero row of K_N.
  bool has_numerical(int s) const;
  // The DOFs (0-based) whose displacement the numerical part of `hosted` needs: `hosted` itself
  // and, through K_N, every DOF coupled to one of them.
  std::vector<int> coupled_to(const std::vector<int>& hosted) const;
  // K_e (N/m, n x n): each experimental part's initial stiffness assembled at its storey or DOF.
  Mat experimental_stiffness() const;
  StoreyAssembly assembly() const;

  HybridPartition() = default;
  HybridPartition(const HybridPartition& other);
  HybridPartition& operator=(const HybridPartition& other);
  HybridPartition(HybridPartition&&) = default;
  HybridPartition& operator=(HybridPartition&&) = default;
};

// Every storey: (1 - alpha) k numerical, alpha k experimental. alpha = 0 gives no actuator,
// alpha = 1 no numerical storey. @pre 0 <= alpha <= 1.
HybridPartition partition_by_fraction(const std::vector<double>& storey_stiffness, double alpha,
                                      const StoreyModelFactory& factory);
// The listed storeys (0-based) are wholly experimental, the rest numerical.
HybridPartition partition_by_storeys(const std::vector<double>& storey_stiffness,
                                     const std::vector<int>& experimental_storeys,
                                     const StoreyModelFactory& factory);

// The experimental parts of a structure given by matrices, each with its specimen model: between
// `dof` (0-based) and the ground when `element` is empty, else an element of that row.
struct DofSpecimen {
  int dof = 0;
  std::unique_ptr<RestoringForceModel> model;
  ElementRow element;
};
// By DOFs: every grounded specimen at its DOF's channel (its model's initial stiffness k_e taken
// out of K at (dof, dof)), every element at channel n + e (k_e b b^T taken out of K), the
// numerical part K_N = K - K_e. Throws std::invalid_argument naming the part when a DOF is
// outside 1..n, a grounded DOF is listed twice, a grounded k_e is not in (0, K(dof, dof)], an
// element's row is empty or zero, or an element leaves K_N with negative stiffness (K - k_e b b^T
// not positive semi-definite: the specimen is stiffer than what it replaces).
HybridPartition partition_by_dofs(const Mat& stiffness, std::vector<DofSpecimen> specimens);
// The same from K held sparse (O(nnz): no n x n copy of a large model).
HybridPartition partition_by_dofs(const SparseMat& stiffness, std::vector<DofSpecimen> specimens);

// Sizes: u and force have dofs() entries, drift, shear and storey tangents storeys() (channels).
// No allocation once the vectors are sized.
class StoreyAssembly {
 public:
  // @pre elements only with by_dofs.
  explicit StoreyAssembly(int storeys, bool by_dofs = false, std::vector<ElementRow> elements = {})
      : n_(storeys), by_dofs_(by_dofs), elements_(std::move(elements)) {}
  void drifts(const Vec& u, Vec& drift) const;  // d_i = u_i - u_{i-1}  (by DOFs: u_i, b_e . u)
  void dof_forces(const Vec& shear, Vec& force) const;    // r_i = V_i - V_{i+1} (by DOFs: V_i +
                                                          // sum_e b_e,i V_{n+e})
  void tangent(const Vec& storey_tangent, Mat& k) const;  // B^T diag(k) B, n x n
  int storeys() const { return n_ + static_cast<int>(elements_.size()); }
  int dofs() const { return n_; }

 private:
  int n_;
  bool by_dofs_;
  std::vector<ElementRow> elements_;
};

class NumericalSubstructure {
 public:
  // `matrix`: the linear K_N of a partition by DOFs (empty: none).
  explicit NumericalSubstructure(std::vector<std::unique_ptr<RestoringForceModel>> storey_models,
                                 RowSparseMat matrix = {});
  explicit NumericalSubstructure(const HybridPartition& partition);
  NumericalSubstructure(const NumericalSubstructure& other);
  // Storey shears at trial drifts (0 where a storey has no numerical part): each storey's model,
  // then + (K_N drift)_s. `storey_tangent` gets the models' tangents only; matrix() is the rest.
  // (K_N drift)_s sums row s's stored entries in column order, one after the other (the same
  // sums in every process, no allocation): O(nnz), and equal to the dense row's sequential dot
  // product for finite drifts (its zero terms add nothing).
  void trial(const Vec& drift, Vec& shear, Vec* storey_tangent);
  void commit();
  void reset();
  int storeys() const { return static_cast<int>(models_.size()); }
  const RowSparseMat& matrix() const { return matrix_; }

 private:
  std::vector<std::unique_ptr<RestoringForceModel>> models_;
  RowSparseMat matrix_;
};

struct ActuatorOutput {
  double realised = 0.0;  // m, the specimen's drift as the displacement sensor reads it
  double force = 0.0;     // N, as the load cell reports it to the integrator
};

// The actuator behind its servo controller (multi-rate). The controller runs `substeps` servo
// periods per integrator step (servo period = dt / substeps; substeps = 1: one per step). Each new
// command starts a linear ramp from the target the servo holds now to the command, reached after
// `substeps` periods, the usual ramp generator of RTHS servo controllers, so the actuator is never
// driven in steps. At servo period j of a ramp (1 <= j <= substeps):
//   target_j = from + (to - from) j / substeps   (displacement, velocity and time alike; j =
//   substeps gives `to` exactly), then the chain (compensation, delay stages, built for the servo
//   period) and the specimen act on target_j. Past the end of a ramp the target stays at `to`
//   and time advances by one servo period per tick.
// step(c) = command(c) then `substeps` ticks, returning the last: the lockstep / in-process form,
// so in-process and distributed lockstep runs of the same multi-rate model agree bit for bit.
// command() + tick() paced by a clock is the real-time form (actuator_emulator's servo loop).
// hold(position, max_change) is the servo controller's interlock: from then on each tick moves the
// target from where it is toward `position` (m) by at most `max_change` (m), with commanded
// velocity = change / servo period, then keeps it there; the chain and the specimen keep acting,
// so the realised drift comes to rest without a jump. Commands after hold() are the caller's to
// refuse (command() is not to be called while holding).
class Actuator {
 public:
  Actuator(DelayChain chain, std::unique_ptr<RestoringForceModel> specimen);
  Actuator(const Actuator& other);
  Actuator& operator=(const Actuator& other);
  Actuator(Actuator&&) = default;
  Actuator& operator=(Actuator&&) = default;
  // @pre substeps >= 1, servo_period > 0 (s). The chain must have been built for servo_period.
  void set_servo(int substeps, double servo_period);
  int servo_substeps() const { return substeps_; }
  ActuatorOutput step(const CommandSample& command);
  void command(const CommandSample& command);
  ActuatorOutput tick();
  // Servo periods since the newest command (0 before the first tick of its ramp).
  int ticks_since_command() const { return ramp_tick_; }
  // @pre max_change > 0 (m per tick).
  void hold(double position, double max_change);
  bool holding() const { return holding_; }
  // The servo's present target displacement (m): mid-ramp, at a command, or on the way to hold.
  double target_displacement() const {
    return holding_ ? hold_target_.displacement : target_at(ramp_tick_).displacement;
  }
  // Holding and the target has reached the hold position.
  bool hold_reached() const { return holding_ && hold_target_.displacement == hold_position_; }
  // Without a delay stage the specimen can be evaluated at trial drifts (implicit reference runs).
  ForceState trial_undelayed(double drift) { return specimen_->trial(drift); }
  void commit_undelayed() { specimen_->commit(); }
  void reset();
  bool has_delay() const { return !chain_.empty(); }
  const DelayChain& chain() const { return chain_; }

 private:
  CommandSample target_at(int tick) const;
  DelayChain chain_;
  std::unique_ptr<RestoringForceModel> specimen_;
  int substeps_ = 1;
  double servo_period_ = 0.0;  // s; 0 = not set (only needed past the end of a ramp)
  CommandSample ramp_from_, ramp_to_;
  int ramp_tick_ = 1;  // ticks of the present ramp done; >= substeps_: at the target
  bool holding_ = false;
  CommandSample hold_target_;     // the target while holding (moves toward hold_position_)
  double hold_position_ = 0.0;    // m
  double hold_max_change_ = 0.0;  // m per tick
};

// Actuator `a` of a partition (at storey actuator_storeys[a]): the chain, a clone of that storey's
// specimen, and the servo loop (servo_substeps periods of dt / servo_substeps per step). The one
// construction in-process runs and the actuator emulator share.
Actuator make_actuator(const HybridPartition& partition, int a, DelayChain chain, double dt,
                       int servo_substeps);

// A restoring-force evaluator for a hybrid run: what the loop records of each step besides forces.
// The restoring force of a hybrid step as the loop thread sees it (core::run_steps calls it once
// per step: set_time, trial, commit). Contract for implementations: no allocation once the first
// step has run (buffers sized at construction); trial() may block, but only for the step's own
// answers (the coordinator's exchange, bounded by its step or feedback window), never for I/O;
// the accessors below return references that stay valid until the next trial().
class HybridEvaluator : public RestoringEvaluator {
 public:
  // Time (s) of the step about to be trialled; experimental parts stamp their commands with it.
  virtual void set_time(double t) = 0;
  // Of the last step, one entry per actuator: commanded drift (m), realised drift (m), force (N).
  virtual const Vec& command() const = 0;
  virtual const Vec& realised() const = 0;
  virtual const Vec& measured_force() const = 0;
  virtual int actuators() const = 0;
  // Of the last step, per actuator: the force predictor's error (N, core/force_predictor.h; 0
  // without one). The force the integrator used is the prediction, measured_force() the
  // measurement.
  virtual const Vec& prediction_error() const = 0;
  // Non-empty when a force predictor's error passed its bound on the last step: the link and
  // the numbers. The loop stops (run_steps), the coordinator's fail-safe HOLDs.
  virtual const std::string& hold() const = 0;
};

// Storey shear = numerical + experimental, in that order, then DOF forces: the one assembly every
// evaluator (local or over a transport) uses, so the sums agree bit for bit.
//   shear (N, per storey) holds the numerical shears on entry and the total on return;
//   measured (N, per actuator) is added at actuator_storeys[a]; force (N, per DOF) is written.
void assemble_storey_forces(const StoreyAssembly& assembly,
                            const std::vector<int>& actuator_storeys, const Vec& measured,
                            Vec& shear, Vec& force);

// In-process restoring force: numerical storeys plus delayed experimental storeys.
// Records, per step, each actuator's commanded drift, realised drift and measured force.
class HybridRestoring final : public HybridEvaluator {
 public:
  // chains: one per actuator (or none), built for the servo period dt / servo_substeps.
  // predictors: one per actuator or none (core/force_predictor.h); empty: none.
  HybridRestoring(const HybridPartition& partition, std::vector<DelayChain> chains, double dt,
                  int servo_substeps = 1,
                  const std::vector<std::optional<PredictorParameters>>& predictors = {});
  const Vec& trial(const Vec& u, const Vec& v, Mat* tangent) override;
  void commit() override;
  bool repeatable() const override;
  void set_time(double t) override { time_ = t; }
  // From now on each step k (= time / dt) hands the integrator the numerical shears and the
  // actuators' outputs of the step `schedule` says the distributed loop used (answer_replay.h), as
  // a real-time run on late answers did; `steps`: the run's. Explicit integrators only.
  void replay_answers(AnswerSchedule schedule, std::size_t steps);

  // Last committed step, one entry per actuator.
  const Vec& command() const override { return command_; }
  const Vec& realised() const override { return realised_; }
  const Vec& measured_force() const override { return measured_; }
  int actuators() const override { return static_cast<int>(actuators_.size()); }
  const Vec& prediction_error() const override { return prediction_error_; }
  const PredictorSet& predictors() const { return predictors_; }
  const std::string& hold() const override { return hold_; }

 private:
  StoreyAssembly assembly_;
  NumericalSubstructure numerical_;
  std::vector<Actuator> actuators_;
  std::vector<int> actuator_storeys_;
  double dt_ = 0.0, time_ = 0.0;
  std::optional<AnswerReplay> replay_;
  Vec drift_, drift_velocity_, shear_, storey_tangent_, force_;
  Vec command_, realised_, measured_;
  PredictorSet predictors_;
  std::vector<long> answer_step_;
  std::vector<std::vector<std::int64_t>> replay_used_;  // the replay's actuator rows
  std::vector<std::string> channel_names_;              // per actuator
  Vec used_, command_rate_, prediction_error_;
  std::string hold_;
};

// Each actuator's declared specimen model (null where a storey has none), in actuator order:
// the shapes force predictors fit (core/force_predictor.h).
std::vector<const RestoringForceModel*> actuator_specimens(const HybridPartition& partition);

// The hold reason of actuator `a` (0-based) whose predictor passed its bound: "force predictor
// of actuator 1 (link of storey 1): relative prediction error 31.2 % over the last 1 s is past
// its bound of 20 % (model k .. +/- .. N/m, c .., ..: ForcePredictor::model_text)", then ": "
// and what the fit says the model lacks
// (ForcePredictor::rejection) when it names something. `link`: how the caller names the link.
std::string predictor_hold_reason(const PredictorSet& predictors, int a, const std::string& link);

}  // namespace rths::core
