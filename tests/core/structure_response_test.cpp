#include "core/structure_response.h"

#include <gtest/gtest.h>

#include <cmath>

#include "study/study.h"

namespace rths::core {
namespace {

// One mode q'' + 2 zeta w q' + w^2 q = p(t), p linear between samples: the closed-form
// recurrence of Nigam & Jennings (1969), as Chopra, Dynamics of Structures, Table 5.2.1 gives it.
Vec nigam_jennings(double w, double zeta, double dt, const std::vector<double>& p) {
  const double k = w * w, s1 = std::sqrt(1.0 - zeta * zeta), wd = w * s1;
  const double e = std::exp(-zeta * w * dt), sn = std::sin(wd * dt), cs = std::cos(wd * dt);
  const double A = e * (zeta / s1 * sn + cs), B = e * sn / wd;
  const double C =
      (2 * zeta / (w * dt) + e * (((1 - 2 * zeta * zeta) / (wd * dt) - zeta / s1) * sn -
                                  (1 + 2 * zeta / (w * dt)) * cs)) /
      k;
  const double D = (1 - 2 * zeta / (w * dt) +
                    e * ((2 * zeta * zeta - 1) / (wd * dt) * sn + 2 * zeta / (w * dt) * cs)) /
                   k;
  const double Ap = -e * w / s1 * sn, Bp = e * (cs - zeta / s1 * sn);
  const double Cp = (-1 / dt + e * ((w / s1 + zeta / (dt * s1)) * sn + cs / dt)) / k;
  const double Dp = (1 - e * (zeta / s1 * sn + cs)) / (k * dt);
  Vec q = Vec::Zero(static_cast<Eigen::Index>(p.size()));
  double u = 0, v = 0;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) {
    const double un = A * u + B * v + C * p[i] + D * p[i + 1];
    v = Ap * u + Bp * v + Cp * p[i] + Dp * p[i + 1];
    u = un;
    q[static_cast<Eigen::Index>(i + 1)] = u;
  }
  return q;
}

// The reference structure of each benchmark case (configs/benchmark), El Centro at 40 % and
// 4096 Hz: the discrete state-space solution equals the modal closed-form one to 1e-6 relative.
TEST(ExactLinearResponse, BenchmarkCasesEqualTheModalClosedFormSolution) {
  for (int c = 1; c <= 4; ++c) {
    const std::filesystem::path config = std::filesystem::path(RTHS_SOURCE_DIR) / "configs" /
                                         "benchmark" / ("case_" + std::to_string(c) + ".textproto");
    config::Study study = study::load_study(config);
    study.mutable_motion()->set_duration(12.0);
    const study::PreparedStudy prepared = study::prepare_study(study, config.parent_path());
    const StructuralModel whole = study::make_structure(study.structure(), config.parent_path());
    const LinearResponse exact = exact_linear_response(whole, prepared.motion);
    ASSERT_NEAR(prepared.motion.dt, 1.0 / 4096, 1e-15);

    const Modes modes = modal_analysis(whole.mass, whole.stiffness);
    Mat modal = Mat::Zero(exact.displacement.rows(), whole.dofs());
    for (int i = 0; i < whole.dofs(); ++i) {
      const Vec phi = modes.shapes.col(i);
      const double w = modes.omega[i];
      const double zeta = phi.dot(whole.damping * phi) / (2 * w);
      const double gamma = phi.dot(whole.mass * whole.influence);
      std::vector<double> p;
      for (double ag : prepared.motion.acceleration) p.push_back(-gamma * ag);
      modal += nigam_jennings(w, zeta, prepared.motion.dt, p) * phi.transpose();
    }
    const double peak = modal.cwiseAbs().maxCoeff();
    EXPECT_GT(peak, 1e-3) << "case " << c;
    EXPECT_LT((exact.displacement - modal).cwiseAbs().maxCoeff(), 1e-6 * peak) << "case " << c;
  }
}

TEST(ExactLinearResponse, RefusesAnEmptyMotion) {
  EXPECT_THROW(exact_linear_response(make_sdof(0.5, 0.05), GroundMotion{}), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
