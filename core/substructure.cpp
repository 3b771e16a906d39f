#include "core/substructure.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/SparseCholesky>

#include "core/number_text.h"

namespace rths::core {
namespace {

std::vector<std::unique_ptr<RestoringForceModel>> clone_all(
    const std::vector<std::unique_ptr<RestoringForceModel>>& models) {
  std::vector<std::unique_ptr<RestoringForceModel>> copies;
  copies.reserve(models.size());
  for (const auto& model : models) copies.push_back(model ? model->clone() : nullptr);
  return copies;
}

}  // namespace

StoreyModelFactory linear_factory() {
  return [](double k) { return std::make_unique<LinearSpring>(k); };
}

std::string ElementRow::describe() const {
  const auto dof_text = [](int j) { return "DOF " + std::to_string(j + 1); };
  if (terms.size() == 2 && terms[0].second == -terms[1].second) {
    const auto& [plus, minus] =
        terms[0].second > 0 ? std::pair{terms[0], terms[1]} : std::pair{terms[1], terms[0]};
    const std::string pair = dof_text(plus.first) + " - " + dof_text(minus.first);
    return plus.second == 1.0 ? pair : format_number(plus.second) + " (" + pair + ")";
  }
  std::string out;
  for (const auto& [j, c] : terms)
    out += (out.empty() ? "" : " + ") + format_number(c) + " " + dof_text(j);
  return out;
}

HybridPartition::HybridPartition(const HybridPartition& other)
    : numerical(clone_all(other.numerical)),
      experimental(clone_all(other.experimental)),
      actuator_storeys(other.actuator_storeys),
      by_dofs(other.by_dofs),
      numerical_matrix(other.numerical_matrix),
      elements(other.elements) {}

std::string HybridPartition::channel_name(int s) const {
  if (s >= dofs())
    return "element " + std::to_string(s - dofs() + 1) + " (" +
           elements[static_cast<std::size_t>(s - dofs())].describe() + ")";
  return (by_dofs ? "DOF " : "storey ") + std::to_string(s + 1);
}

bool HybridPartition::has_numerical(int s) const {
  if (numerical[static_cast<std::size_t>(s)]) return true;
  if (s >= numerical_matrix.rows()) return false;
  for (RowSparseMat::InnerIterator it(numerical_matrix, s); it; ++it)
    if (it.value() != 0.0) return true;
  return false;
}

std::vector<int> HybridPartition::coupled_to(const std::vector<int>& hosted) const {
  std::vector<bool> needed(numerical.size(), false);
  for (int s : hosted) {
    needed[static_cast<std::size_t>(s)] = true;
    if (s >= numerical_matrix.rows()) continue;
    for (RowSparseMat::InnerIterator it(numerical_matrix, s); it; ++it)
      if (it.value() != 0.0) needed[static_cast<std::size_t>(it.col())] = true;
  }
  std::vector<int> out;
  for (std::size_t s = 0; s < needed.size(); ++s)
    if (needed[s]) out.push_back(static_cast<int>(s));
  return out;
}

Mat HybridPartition::experimental_stiffness() const {
  const int n = static_cast<int>(experimental.size());
  Vec k = Vec::Zero(n);
  for (int s = 0; s < n; ++s)
    if (experimental[static_cast<std::size_t>(s)])
      k[s] = experimental[static_cast<std::size_t>(s)]->initial_stiffness();
  Mat out;
  assembly().tangent(k, out);
  return out;
}

StoreyAssembly HybridPartition::assembly() const {
  return StoreyAssembly(dofs(), by_dofs, elements);
}

namespace {

// A grounded specimen at its DOF's channel: k_e in (0, K(d, d)] taken out of K_N at (d, d).
void place_grounded(HybridPartition& partition, SparseMat& numerical, const SparseMat& stiffness,
                    DofSpecimen& specimen) {
  const int d = specimen.dof, n = static_cast<int>(stiffness.rows());
  const std::string name = "experimental DOF " + std::to_string(d + 1);
  if (d < 0 || d >= n) throw std::invalid_argument(name + " is outside 1.." + std::to_string(n));
  if (partition.experimental[static_cast<std::size_t>(d)])
    throw std::invalid_argument(name + " is listed twice");
  const double k = specimen.model->initial_stiffness();
  const double diagonal = stiffness.coeff(d, d);
  if (!(k > 0 && k <= diagonal))
    throw std::invalid_argument(name + ": stiffness " + format_number(k) +
                                " N/m must be in (0, K(" + std::to_string(d + 1) + ", " +
                                std::to_string(d + 1) + ") = " + format_number(diagonal) + "]");
  numerical.coeffRef(d, d) -= k;
  partition.experimental[static_cast<std::size_t>(d)] = std::move(specimen.model);
}

// An element at the next channel: k_e b b^T taken out of K_N.
void place_element(HybridPartition& partition, SparseMat& numerical, DofSpecimen& specimen) {
  const int n = static_cast<int>(numerical.rows());
  const std::string name = "experimental element " + std::to_string(partition.elements.size() + 1);
  bool nonzero = false;
  for (const auto& [j, c] : specimen.element.terms) {
    if (j < 0 || j >= n)
      throw std::invalid_argument(name + ": DOF " + std::to_string(j + 1) + " is outside 1.." +
                                  std::to_string(n));
    if (!std::isfinite(c)) throw std::invalid_argument(name + ": a coefficient is not finite");
    nonzero = nonzero || c != 0.0;
  }
  if (!nonzero) throw std::invalid_argument(name + ": its influence row is zero");
  const double k = specimen.model->initial_stiffness();
  if (!(k > 0 && std::isfinite(k)))
    throw std::invalid_argument(name + ": stiffness " + format_number(k) + " N/m must be > 0");
  for (const auto& [i, ci] : specimen.element.terms)
    for (const auto& [j, cj] : specimen.element.terms) numerical.coeffRef(i, j) -= k * ci * cj;
  partition.elements.push_back(specimen.element);
  partition.numerical.push_back(nullptr);
  partition.experimental.push_back(std::move(specimen.model));
}

// K_N = K - K_e positive semi-definite (relative to K's scale): no element stiffer than what it
// replaces. Only checked with elements (a grounded k_e <= K(d, d) is its own bound). Judged by the
// pivots of a sparse LDL^T of K_N shifted by 1e-9 of K's scale (all positive exactly when the
// shifted matrix is positive definite): O(nnz) for a large sparse model.
void check_numerical_semidefinite(const HybridPartition& partition, const SparseMat& numerical,
                                  const SparseMat& stiffness) {
  if (partition.elements.empty()) return;
  double scale = 0.0;
  for (Eigen::Index j = 0; j < stiffness.outerSize(); ++j)
    for (SparseMat::InnerIterator it(stiffness, j); it; ++it)
      scale = std::max(scale, std::abs(it.value()));
  Eigen::SparseMatrix<double> shifted = numerical;
  for (Eigen::Index i = 0; i < shifted.rows(); ++i) shifted.coeffRef(i, i) += 1e-9 * scale;
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor(shifted);
  const double lowest = factor.info() == Eigen::Success ? factor.vectorD().minCoeff() : -scale;
  if (!(lowest > 0))
    throw std::invalid_argument(
        "the experimental elements are stiffer than the structure they replace: K - K_e is not "
        "positive semi-definite (a pivot of its LDL^T is " +
        format_number(lowest - 1e-9 * scale) + " N/m; K's largest entry " + format_number(scale) +
        " N/m); check each element's stiffness against the storey or member it sits in");
}

}  // namespace

HybridPartition partition_by_dofs(const Mat& stiffness, std::vector<DofSpecimen> specimens) {
  return partition_by_dofs(SparseMat(stiffness.sparseView()), std::move(specimens));
}

HybridPartition partition_by_dofs(const SparseMat& stiffness, std::vector<DofSpecimen> specimens) {
  const int n = static_cast<int>(stiffness.rows());
  HybridPartition partition;
  partition.by_dofs = true;
  partition.numerical.resize(static_cast<std::size_t>(n));
  partition.experimental.resize(static_cast<std::size_t>(n));
  SparseMat numerical = stiffness;
  for (DofSpecimen& specimen : specimens) {
    if (!specimen.model) throw std::invalid_argument("an experimental part has no specimen model");
    if (specimen.element.terms.empty())
      place_grounded(partition, numerical, stiffness, specimen);
    else
      place_element(partition, numerical, specimen);
  }
  check_numerical_semidefinite(partition, numerical, stiffness);
  for (int s = 0; s < partition.channels(); ++s)
    if (partition.experimental[static_cast<std::size_t>(s)])
      partition.actuator_storeys.push_back(s);
  numerical.prune(0.0);  // exact zeros dropped
  partition.numerical_matrix = numerical;
  return partition;
}

HybridPartition& HybridPartition::operator=(const HybridPartition& other) {
  if (this != &other) *this = HybridPartition(other);
  return *this;
}

HybridPartition partition_by_fraction(const std::vector<double>& storey_stiffness, double alpha,
                                      const StoreyModelFactory& factory) {
  if (!(alpha >= 0.0 && alpha <= 1.0)) {
    throw std::invalid_argument("experimental_fraction must be in [0, 1], got " +
                                std::to_string(alpha));
  }
  HybridPartition partition;
  for (std::size_t s = 0; s < storey_stiffness.size(); ++s) {
    const double k = storey_stiffness[s];
    partition.numerical.push_back(alpha < 1.0 ? factory((1.0 - alpha) * k) : nullptr);
    partition.experimental.push_back(alpha > 0.0 ? factory(alpha * k) : nullptr);
    if (alpha > 0.0) partition.actuator_storeys.push_back(static_cast<int>(s));
  }
  return partition;
}

HybridPartition partition_by_storeys(const std::vector<double>& storey_stiffness,
                                     const std::vector<int>& experimental_storeys,
                                     const StoreyModelFactory& factory) {
  const int n = static_cast<int>(storey_stiffness.size());
  std::vector<bool> experimental(n, false);
  for (int s : experimental_storeys) {
    if (s < 0 || s >= n) {
      throw std::invalid_argument("experimental storey " + std::to_string(s + 1) +
                                  " is outside 1.." + std::to_string(n));
    }
    if (experimental[s]) {
      throw std::invalid_argument("experimental storey " + std::to_string(s + 1) +
                                  " is listed twice");
    }
    experimental[s] = true;
  }
  HybridPartition partition;
  for (int s = 0; s < n; ++s) {
    partition.numerical.push_back(experimental[s] ? nullptr : factory(storey_stiffness[s]));
    partition.experimental.push_back(experimental[s] ? factory(storey_stiffness[s]) : nullptr);
    if (experimental[s]) partition.actuator_storeys.push_back(s);
  }
  return partition;
}

void StoreyAssembly::drifts(const Vec& u, Vec& drift) const {
  if (by_dofs_) {
    drift.head(n_) = u;
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      double x = 0.0;
      for (const auto& [j, c] : elements_[e].terms) x += c * u[j];
      drift[n_ + static_cast<int>(e)] = x;
    }
    return;
  }
  drift[0] = u[0];
  for (int i = 1; i < n_; ++i) drift[i] = u[i] - u[i - 1];
}

void StoreyAssembly::dof_forces(const Vec& shear, Vec& force) const {
  if (by_dofs_) {
    force = shear.head(n_);
    for (std::size_t e = 0; e < elements_.size(); ++e)
      for (const auto& [j, c] : elements_[e].terms) force[j] += c * shear[n_ + static_cast<int>(e)];
    return;
  }
  for (int i = 0; i + 1 < n_; ++i) force[i] = shear[i] - shear[i + 1];
  force[n_ - 1] = shear[n_ - 1];
}

void StoreyAssembly::tangent(const Vec& storey_tangent, Mat& k) const {
  k.setZero(n_, n_);
  for (int s = 0; s < n_; ++s) {
    k(s, s) += storey_tangent[s];
    if (s > 0 && !by_dofs_) {
      k(s - 1, s - 1) += storey_tangent[s];
      k(s - 1, s) -= storey_tangent[s];
      k(s, s - 1) -= storey_tangent[s];
    }
  }
  for (std::size_t e = 0; e < elements_.size(); ++e) {
    const double ke = storey_tangent[n_ + static_cast<int>(e)];
    for (const auto& [i, ci] : elements_[e].terms)
      for (const auto& [j, cj] : elements_[e].terms) k(i, j) += ke * ci * cj;
  }
}

NumericalSubstructure::NumericalSubstructure(
    std::vector<std::unique_ptr<RestoringForceModel>> storey_models, RowSparseMat matrix)
    : models_(std::move(storey_models)), matrix_(std::move(matrix)) {}

NumericalSubstructure::NumericalSubstructure(const HybridPartition& partition)
    : models_(clone_all(partition.numerical)), matrix_(partition.numerical_matrix) {}

NumericalSubstructure::NumericalSubstructure(const NumericalSubstructure& other)
    : models_(clone_all(other.models_)), matrix_(other.matrix_) {}

void NumericalSubstructure::trial(const Vec& drift, Vec& shear, Vec* storey_tangent) {
  for (std::size_t s = 0; s < models_.size(); ++s) {
    ForceState state;
    if (models_[s]) state = models_[s]->trial(drift[s]);
    shear[s] = state.force;
    if (storey_tangent) (*storey_tangent)[s] = state.tangent;
  }
  // Row by row, the same sums in every process (no allocation, no reordering by size).
  for (Eigen::Index i = 0; i < matrix_.outerSize(); ++i) {
    double sum = 0.0;
    for (RowSparseMat::InnerIterator it(matrix_, i); it; ++it) sum += it.value() * drift[it.col()];
    shear[i] += sum;
  }
}

void NumericalSubstructure::commit() {
  for (auto& model : models_) {
    if (model) model->commit();
  }
}

void NumericalSubstructure::reset() {
  for (auto& model : models_) {
    if (model) model->reset();
  }
}

Actuator::Actuator(DelayChain chain, std::unique_ptr<RestoringForceModel> specimen)
    : chain_(std::move(chain)), specimen_(std::move(specimen)) {
  if (!specimen_) throw std::invalid_argument("an actuator needs a specimen model");
}

Actuator::Actuator(const Actuator& other)
    : chain_(other.chain_),
      specimen_(other.specimen_->clone()),
      substeps_(other.substeps_),
      servo_period_(other.servo_period_),
      ramp_from_(other.ramp_from_),
      ramp_to_(other.ramp_to_),
      ramp_tick_(other.ramp_tick_),
      holding_(other.holding_),
      hold_target_(other.hold_target_),
      hold_position_(other.hold_position_),
      hold_max_change_(other.hold_max_change_) {}

Actuator& Actuator::operator=(const Actuator& other) {
  if (this != &other) *this = Actuator(other);
  return *this;
}

void Actuator::set_servo(int substeps, double servo_period) {
  if (substeps < 1) throw std::invalid_argument("a servo loop needs at least one period per step");
  if (!(servo_period > 0)) throw std::invalid_argument("the servo period must be > 0 s");
  substeps_ = substeps;
  servo_period_ = servo_period;
  ramp_tick_ = substeps_;
}

CommandSample Actuator::target_at(int tick) const {
  CommandSample target = ramp_to_;
  if (tick < substeps_) {
    const double f = static_cast<double>(tick) / substeps_;
    target.time = ramp_from_.time + (ramp_to_.time - ramp_from_.time) * f;
    target.displacement =
        ramp_from_.displacement + (ramp_to_.displacement - ramp_from_.displacement) * f;
    target.velocity = ramp_from_.velocity + (ramp_to_.velocity - ramp_from_.velocity) * f;
  } else if (tick > substeps_) {
    target.time += (tick - substeps_) * servo_period_;
  }
  return target;
}

void Actuator::command(const CommandSample& command) {
  // The ramp starts where the servo's target is now (mid-ramp when a command comes early).
  ramp_from_ = target_at(ramp_tick_);
  ramp_to_ = command;
  ramp_tick_ = 0;
}

void Actuator::hold(double position, double max_change) {
  if (!(max_change > 0))
    throw std::invalid_argument("a hold ramp needs a positive rate (m per tick)");
  if (!holding_) hold_target_ = target_at(ramp_tick_);
  holding_ = true;
  hold_position_ = position;
  hold_max_change_ = max_change;
}

ActuatorOutput Actuator::tick() {
  CommandSample target;
  if (holding_) {
    const double change =
        std::clamp(hold_position_ - hold_target_.displacement, -hold_max_change_, hold_max_change_);
    // Landing exactly on the hold position (not within rounding) makes hold_reached() exact.
    hold_target_.displacement =
        std::abs(hold_position_ - hold_target_.displacement) <= hold_max_change_
            ? hold_position_
            : hold_target_.displacement + change;
    hold_target_.velocity = servo_period_ > 0 ? change / servo_period_ : 0.0;
    hold_target_.time += servo_period_;
    target = hold_target_;
  } else {
    target = target_at(++ramp_tick_);
  }
  ActuatorOutput out;
  if (chain_.empty()) {
    out.realised = target.displacement;
    out.force = specimen_->step(out.realised);
    return out;
  }
  // The specimen moves with the chain's output; the controller reports its sensors' readings.
  out.force = chain_.measure_force(specimen_->step(chain_.step(target)));
  out.realised = chain_.measured();
  return out;
}

ActuatorOutput Actuator::step(const CommandSample& command) {
  this->command(command);
  ActuatorOutput out;
  for (int j = 0; j < substeps_; ++j) out = tick();
  return out;
}

void Actuator::reset() {
  chain_.reset();
  specimen_->reset();
  ramp_from_ = ramp_to_ = CommandSample{};
  ramp_tick_ = substeps_;
  holding_ = false;
}

void assemble_storey_forces(const StoreyAssembly& assembly,
                            const std::vector<int>& actuator_storeys, const Vec& measured,
                            Vec& shear, Vec& force) {
  for (std::size_t a = 0; a < actuator_storeys.size(); ++a)
    shear[actuator_storeys[a]] += measured[static_cast<Eigen::Index>(a)];
  assembly.dof_forces(shear, force);
}

Actuator make_actuator(const HybridPartition& partition, int a, DelayChain chain, double dt,
                       int servo_substeps) {
  if (a < 0 || a >= static_cast<int>(partition.actuator_storeys.size()))
    throw std::invalid_argument("actuator " + std::to_string(a) + " does not exist");
  const int storey = partition.actuator_storeys[static_cast<std::size_t>(a)];
  Actuator actuator(std::move(chain),
                    partition.experimental[static_cast<std::size_t>(storey)]->clone());
  actuator.set_servo(servo_substeps, dt / servo_substeps);
  return actuator;
}

HybridRestoring::HybridRestoring(const HybridPartition& partition, std::vector<DelayChain> chains,
                                 double dt, int servo_substeps,
                                 const std::vector<std::optional<PredictorParameters>>& predictors)
    : assembly_(partition.assembly()),
      numerical_(partition),
      actuator_storeys_(partition.actuator_storeys),
      dt_(dt),
      predictors_(predictors, dt, actuator_specimens(partition)) {
  if (!predictors.empty() && predictors.size() != partition.actuator_storeys.size())
    throw std::invalid_argument(std::to_string(predictors.size()) + " force predictors for " +
                                std::to_string(partition.actuator_storeys.size()) + " actuators");
  const std::size_t actuators = partition.actuator_storeys.size();
  if (!chains.empty() && chains.size() != actuators) {
    throw std::invalid_argument(std::to_string(chains.size()) + " delay chains for " +
                                std::to_string(actuators) + " actuators");
  }
  chains.resize(actuators);
  for (std::size_t a = 0; a < actuators; ++a)
    actuators_.push_back(
        make_actuator(partition, static_cast<int>(a), std::move(chains[a]), dt, servo_substeps));
  const int n = assembly_.storeys();
  drift_ = Vec::Zero(n);
  drift_velocity_ = Vec::Zero(n);
  shear_ = Vec::Zero(n);
  storey_tangent_ = Vec::Zero(n);
  force_ = Vec::Zero(assembly_.dofs());
  command_ = Vec::Zero(static_cast<int>(actuators));
  realised_ = Vec::Zero(static_cast<int>(actuators));
  measured_ = Vec::Zero(static_cast<int>(actuators));
  used_ = Vec::Zero(static_cast<int>(actuators));
  command_rate_ = Vec::Zero(static_cast<int>(actuators));
  prediction_error_ = Vec::Zero(static_cast<int>(actuators));
  answer_step_.assign(actuators, -1);
  for (int s : actuator_storeys_) channel_names_.push_back(partition.channel_name(s));
}

bool HybridRestoring::repeatable() const {
  for (const Actuator& actuator : actuators_) {
    if (actuator.has_delay()) return false;
  }
  return true;
}

const Vec& HybridRestoring::trial(const Vec& u, const Vec& v, Mat* tangent) {
  assembly_.drifts(u, drift_);
  assembly_.drifts(v, drift_velocity_);
  numerical_.trial(drift_, shear_, tangent ? &storey_tangent_ : nullptr);
  for (std::size_t a = 0; a < actuators_.size(); ++a) {
    const int s = actuator_storeys_[a];
    if (tangent) {
      // Implicit iteration (only when undelayed): evaluate without committing.
      const ForceState state = actuators_[a].trial_undelayed(drift_[s]);
      measured_[a] = state.force;
      storey_tangent_[s] += state.tangent;
    } else {
      const ActuatorOutput out = actuators_[a].step({time_, drift_[s], drift_velocity_[s]});
      command_[a] = drift_[s];
      realised_[a] = out.realised;
      measured_[a] = out.force;
    }
  }
  const auto step = static_cast<std::size_t>(std::llround(time_ / dt_));
  if (replay_ && !tangent) replay_->step(step, shear_, realised_, measured_);
  if (predictors_.empty() || tangent) {
    assemble_storey_forces(assembly_, actuator_storeys_, measured_, shear_, force_);
  } else {
    // The answer each actuator's pair describes: this step's, or the one a replay used (0 there:
    // none yet, as the coordinator's intake reports it).
    for (std::size_t a = 0; a < answer_step_.size(); ++a) {
      answer_step_[a] = static_cast<long>(step);
      if (replay_ && a < replay_used_.size() && !replay_used_[a].empty())
        answer_step_[a] = replay_used_[a][step] > 0 ? static_cast<long>(replay_used_[a][step]) : -1;
      command_rate_[static_cast<Eigen::Index>(a)] = drift_velocity_[actuator_storeys_[a]];
    }
    const int exceeded = predictors_.apply(command_, command_rate_, answer_step_, realised_,
                                           measured_, used_, prediction_error_);
    if (exceeded >= 0 && hold_.empty())
      hold_ = predictor_hold_reason(
          predictors_, exceeded, "link of " + channel_names_[static_cast<std::size_t>(exceeded)]);
    assemble_storey_forces(assembly_, actuator_storeys_, used_, shear_, force_);
  }
  if (tangent) {
    assembly_.tangent(storey_tangent_, *tangent);
    if (numerical_.matrix().size() > 0) *tangent += numerical_.matrix();
  }
  return force_;
}

void HybridRestoring::commit() { numerical_.commit(); }

std::vector<const RestoringForceModel*> actuator_specimens(const HybridPartition& partition) {
  std::vector<const RestoringForceModel*> out;
  for (int s : partition.actuator_storeys)
    out.push_back(partition.experimental[static_cast<std::size_t>(s)].get());
  return out;
}

std::string predictor_hold_reason(const PredictorSet& predictors, int a, const std::string& link) {
  const auto i = static_cast<std::size_t>(a);
  const PredictorParameters& p = predictors.at(i).parameters();
  std::ostringstream text;
  text << std::setprecision(3) << "force predictor of actuator " << a + 1 << " (" << link
       << "): relative prediction error " << 100.0 * predictors.last(i).relative_error
       << " % over the last " << p.error_window << " s is past its bound of "
       << 100.0 * p.max_relative_error << " % (model " << predictors.at(i).model_text() << ")";
  // What the fit says the model lacks, so the HOLD names the missing term, not only the figure.
  const std::string lacks = predictors.at(i).rejection();
  if (!lacks.empty()) text << ": " << lacks;
  return text.str();
}

void HybridRestoring::replay_answers(AnswerSchedule schedule, std::size_t steps) {
  replay_used_ = schedule.actuator_used;
  replay_.emplace(std::move(schedule), assembly_.storeys(), actuators(), steps);
}

}  // namespace rths::core
