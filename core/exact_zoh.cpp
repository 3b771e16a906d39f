#include "core/exact_zoh.h"

#include <stdexcept>
#include <string>

#include <unsupported/Eigen/MatrixFunctions>

namespace rths::core {

ExactDiscretisation exact_discretisation(const Mat& mass, const Mat& damping, const Mat& stiffness,
                                         double h) {
  const Eigen::Index n = mass.rows();
  const Mat mass_inverse = mass.ldlt().solve(Mat::Identity(n, n));
  Mat augmented = Mat::Zero(4 * n, 4 * n);
  augmented.block(0, n, n, n) = Mat::Identity(n, n);
  augmented.block(n, 0, n, n) = -mass_inverse * stiffness;
  augmented.block(n, n, n, n) = -mass_inverse * damping;
  augmented.block(n, 2 * n, n, n) = mass_inverse;
  augmented.block(2 * n, 3 * n, n, n) = Mat::Identity(n, n) / h;
  const Mat e = (augmented * h).exp();
  return {e.topLeftCorner(2 * n, 2 * n), e.block(0, 2 * n, 2 * n, n), e.block(0, 3 * n, 2 * n, n)};
}

namespace {

class ExactZohIntegrator final : public Integrator {
 public:
  ExactZohIntegrator(const StructuralModel& model, double dt, const Mat& exact_stiffness)
      : Integrator(model, dt),
        k_exact_(exact_stiffness),
        step_(exact_discretisation(m_, c_, exact_stiffness, dt)),
        mass_inverse_(m_.inverse()) {
    const Eigen::Index n = m_.rows();
    held_ = Vec::Zero(n);
    load_ = Vec::Zero(n);
    input_ = Vec::Zero(n);
    slope_ = Vec::Zero(n);
    state_ = Vec::Zero(2 * n);
    next_ = Vec::Zero(2 * n);
  }
  IntegratorKind kind() const override { return IntegratorKind::kExactZoh; }

  void initialize(const Vec& u0, const Vec& v0, const Vec& r0, const Vec& p0) override {
    u_ = u0;
    v_ = v0;
    a_.noalias() = mass_inverse_ * (p0 - c_ * v0 - r0);
    held_ = r0;
    held_.noalias() -= k_exact_ * u0;
    load_ = p0;
  }

  void step(const Vec& load_next, RestoringEvaluator& restoring) override {
    const Eigen::Index n = u_.size();
    state_.head(n) = u_;
    state_.tail(n) = v_;
    input_ = load_ - held_;
    slope_ = load_next - load_;
    next_.noalias() = step_.phi * state_;
    next_.noalias() += step_.gamma0 * input_;
    next_.noalias() += step_.gamma1 * slope_;
    u_ = next_.head(n);
    v_ = next_.tail(n);
    const Vec& r = restoring.trial(u_, v_, nullptr);
    restoring.commit();
    held_ = r;
    held_.noalias() -= k_exact_ * u_;
    input_ = load_next - r;
    input_.noalias() -= c_ * v_;
    a_.noalias() = mass_inverse_ * input_;
    load_ = load_next;
  }

 private:
  Mat k_exact_;
  ExactDiscretisation step_;
  Mat mass_inverse_;
  Vec held_, load_, input_, slope_, state_, next_;
};

}  // namespace

std::unique_ptr<Integrator> make_exact_zoh_integrator(const StructuralModel& model, double dt,
                                                      const Mat& exact_stiffness) {
  if (exact_stiffness.rows() != model.dofs() || exact_stiffness.cols() != model.dofs()) {
    std::string message = "exact-zoh: the exactly integrated stiffness is ";
    message += std::to_string(exact_stiffness.rows()) + " x " +
               std::to_string(exact_stiffness.cols()) + ", the model has ";
    message += std::to_string(model.dofs()) + " DOFs";
    throw std::invalid_argument(message);
  }
  if (!(dt > 0)) throw std::invalid_argument("time step dt must be > 0 s");
  return std::make_unique<ExactZohIntegrator>(model, dt, exact_stiffness);
}

}  // namespace rths::core
