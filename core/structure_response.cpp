#include "core/structure_response.h"

#include <stdexcept>

#include <unsupported/Eigen/MatrixFunctions>

namespace rths::core {

LinearResponse exact_linear_response(const StructuralModel& model, const GroundMotion& motion) {
  const Eigen::Index n = model.mass.rows();
  const double dt = motion.dt;
  if (!(dt > 0) || motion.acceleration.empty())
    throw std::invalid_argument("exact linear response: the motion needs samples and a step > 0 s");
  const Eigen::LDLT<Mat> mass(model.mass);
  Mat augmented = Mat::Zero(2 * n + 2, 2 * n + 2);
  augmented.block(0, n, n, n) = Mat::Identity(n, n);
  augmented.block(n, 0, n, n) = -mass.solve(model.stiffness);
  augmented.block(n, n, n, n) = -mass.solve(model.damping);
  augmented.block(n, 2 * n, n, 1) = -model.influence;
  augmented(2 * n, 2 * n + 1) = 1.0;
  const Mat e = (augmented * dt).exp();
  const Mat phi = e.topLeftCorner(2 * n, 2 * n);
  const Vec g0 = e.block(0, 2 * n, 2 * n, 1);
  const Vec g1 = e.block(0, 2 * n + 1, 2 * n, 1);
  const auto samples = static_cast<Eigen::Index>(motion.acceleration.size());
  LinearResponse out;
  out.dt = dt;
  out.displacement.resize(samples, n);
  out.velocity.resize(samples, n);
  out.acceleration.resize(samples, n);
  Vec x = Vec::Zero(2 * n), next(2 * n);
  for (Eigen::Index k = 0; k < samples; ++k) {
    const double ag = motion.acceleration[static_cast<std::size_t>(k)];
    out.displacement.row(k) = x.head(n).transpose();
    out.velocity.row(k) = x.tail(n).transpose();
    out.acceleration.row(k) =
        (-mass.solve(model.stiffness * x.head(n) + model.damping * x.tail(n)) -
         model.influence * ag)
            .transpose();
    if (k + 1 == samples) break;
    const double slope = (motion.acceleration[static_cast<std::size_t>(k + 1)] - ag) / dt;
    next.noalias() = phi * x + g0 * ag + g1 * slope;
    x.swap(next);
  }
  return out;
}

}  // namespace rths::core
