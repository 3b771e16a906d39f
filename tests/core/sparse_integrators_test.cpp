#include "core/sparse_integrators.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <numbers>
#include <vector>

#include "core/integrators.h"
#include "core/sparse_structure.h"
#include "core/structure.h"
#include "core/substructure.h"

// Counts every allocation of this test program, so a step can be shown to allocate nothing.
namespace {
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace rths::core {
namespace {

// r = K u through a sparse K, as a large model's numerical part gives it; allocation-free.
class SparseLinearEvaluator final : public RestoringEvaluator {
 public:
  explicit SparseLinearEvaluator(SparseMat k) : k_(std::move(k)), force_(Vec::Zero(k_.rows())) {}
  const Vec& trial(const Vec& u, const Vec&, Mat*) override {
    force_.noalias() = k_ * u;
    return force_;
  }
  void commit() override {}
  bool repeatable() const override { return true; }

 private:
  SparseMat k_;
  Vec force_;
};

// A shear building of n storeys with stiffness and mass varying up the height, Rayleigh damped
// (5 % in modes 1 and 2), held dense; the same model held sparse only.
StructuralModel dense_building(int n) {
  std::vector<double> mass, stiffness;
  for (int i = 0; i < n; ++i) {
    mass.push_back(1e4 * (1.0 + 0.1 * (i % 3)));
    stiffness.push_back(2e7 * (1.0 + 0.05 * (n - i) / n));
  }
  StructuralModel model = make_shear_building(mass, stiffness);
  model.damping = rayleigh_damping(model.mass, model.stiffness, 0.05, 1, 2);
  return model;
}

StructuralModel sparse_copy(const StructuralModel& dense) {
  return make_sparse_model(dense.mass.sparseView(), dense.damping.sparseView(),
                           dense.stiffness.sparseView(), dense.influence);
}

// Displacement history under a ground-motion pulse train, every DOF, every step.
Mat response(IntegratorKind kind, const StructuralModel& model, double dt, int steps) {
  IntegratorParameters parameters;
  parameters.alpha_os = 0.9;
  parameters.rho_infinity = 0.6;
  auto integrator = make_integrator(kind, model, dt, parameters);
  const SparseMat k =
      model.is_sparse() ? model.sparse_stiffness : SparseMat(model.stiffness.sparseView());
  SparseLinearEvaluator evaluator(k);
  const Vec mass_iota = mass_times(model, model.influence);
  const int n = model.dofs();
  integrator->initialize(Vec::Zero(n), Vec::Zero(n), Vec::Zero(n), Vec::Zero(n));
  Mat out(steps, n);
  for (int s = 0; s < steps; ++s) {
    const double ground = std::sin(0.05 * s) * (s < steps / 2 ? 3.0 : 0.0);
    integrator->step(-mass_iota * ground, evaluator);
    out.row(s) = integrator->displacement().transpose();
  }
  return out;
}

constexpr IntegratorKind kSparseKinds[] = {
    IntegratorKind::kExplicitNewmark, IntegratorKind::kCentralDifference,
    IntegratorKind::kChenRicles, IntegratorKind::kAlphaOS, IntegratorKind::kKRAlpha};

TEST(SparseIntegrators, EqualTheDenseSchemesToRoundingForTenToFiftyDofs) {
  for (int n : {10, 25, 50}) {
    const StructuralModel dense = dense_building(n);
    const StructuralModel sparse = sparse_copy(dense);
    ASSERT_TRUE(sparse.is_sparse());
    ASSERT_FALSE(dense.is_sparse());
    const double dt = 1.0 / 1024;
    for (IntegratorKind kind : kSparseKinds) {
      const Mat expected = response(kind, dense, dt, 400);
      const Mat got = response(kind, sparse, dt, 400);
      const double scale = expected.cwiseAbs().maxCoeff();
      ASSERT_GT(scale, 1e-6) << to_string(kind);
      EXPECT_LE((got - expected).cwiseAbs().maxCoeff(), 1e-12 * scale)
          << to_string(kind) << " at n = " << n;
    }
  }
}

TEST(SparseIntegrators, StepWithoutAllocating) {
  StructuralModel rayleigh = sparse_copy(dense_building(300)), modal = rayleigh;
  sparse_modal_damping(modal, 0.05);  // C's low-rank part too
  for (const StructuralModel& model : {rayleigh, modal})
    for (IntegratorKind kind : kSparseKinds) {
      SparseLinearEvaluator evaluator(model.sparse_stiffness);
      const Vec load = Vec::Constant(model.dofs(), 1e3);
      auto integrator = make_integrator(kind, model, 1.0 / 1024);
      integrator->initialize(Vec::Zero(300), Vec::Zero(300), Vec::Zero(300), load);
      const long before = allocations.load();
      for (int s = 0; s < 50; ++s) integrator->step(load, evaluator);
      EXPECT_EQ(allocations.load() - before, 0) << to_string(kind);
      EXPECT_TRUE(integrator->displacement().allFinite());
    }
}

TEST(SparseIntegrators, DenseOnlySchemesRefuseModalDampingKeptAsFactorsNamingTheFix) {
  StructuralModel model = dense_building(150);  // dense copies held too
  const StructuralModel sparse = sparse_copy(model);
  model.sparse_mass = sparse.sparse_mass;
  model.sparse_damping = sparse.sparse_damping;
  model.sparse_stiffness = sparse.sparse_stiffness;
  sparse_modal_damping(model, 0.05);
  for (IntegratorKind kind :
       {IntegratorKind::kExactZoh, IntegratorKind::kNewmarkAverageAcceleration}) {
    try {
      make_integrator(kind, model, 0.01);
      FAIL() << to_string(kind) << " took modal damping kept as factors";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("kept as factors"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("explicit integrator"), std::string::npos) << e.what();
    }
  }
}

// The coordinator's step on a large model: the sparse integrator and the in-process restoring
// force (a 2000-DOF sparse K_N, one actuator) together allocate nothing per step.
TEST(SparseIntegrators, ALargeHybridStepAllocatesNothing) {
  const int n = 2000;
  StructuralModel model =
      sparse_copy(make_shear_building(std::vector<double>(n, 1e4), std::vector<double>(n, 2e7)));
  sparse_rayleigh_damping(model, 0.05, 1, 2);
  HybridPartition partition;
  partition.by_dofs = true;
  partition.numerical.resize(n);
  partition.experimental.resize(n);
  partition.experimental[0] = std::make_unique<LinearSpring>(1e6);
  partition.actuator_storeys = {0};
  partition.numerical_matrix = model.sparse_stiffness;
  partition.numerical_matrix.coeffRef(0, 0) -= 1e6;
  HybridRestoring restoring(partition, {}, 1.0 / 1024);
  auto integrator = make_integrator(IntegratorKind::kExplicitNewmark, model, 1.0 / 1024);
  const Vec load = Vec::Constant(n, 1e3);
  integrator->initialize(Vec::Zero(n), Vec::Zero(n), Vec::Zero(n), load);
  restoring.set_time(0.0);
  integrator->step(load, restoring);  // the first step may size what it keeps
  const long before = allocations.load();
  for (int s = 1; s < 50; ++s) {
    restoring.set_time(s / 1024.0);
    integrator->step(load, restoring);
  }
  EXPECT_EQ(allocations.load() - before, 0);
  EXPECT_GT(integrator->displacement().cwiseAbs().maxCoeff(), 0.0);
}

// A sparse-only building with modal damping through its lowest modes, and the same model held
// dense with C = a1 K + B diag(c) B^T formed (only a test forms it).
struct ModalPair {
  StructuralModel sparse, dense;
};
ModalPair modal_pair(int n, double zeta) {
  ModalPair pair;
  pair.dense = dense_building(n);
  pair.sparse = sparse_copy(pair.dense);
  sparse_modal_damping(pair.sparse, zeta);
  const LowRankDamping& low = pair.sparse.low_rank_damping;
  pair.dense.damping = Mat(pair.sparse.sparse_damping) +
                       low.basis * low.coefficients.asDiagonal() * low.basis.transpose();
  return pair;
}

TEST(SparseIntegrators, StepModalDampingAsFactorsAsTheDenseSchemesStepItFormed) {
  const ModalPair pair = modal_pair(150, 0.05);
  ASSERT_FALSE(pair.sparse.low_rank_damping.empty());
  for (IntegratorKind kind : kSparseKinds) {
    const Mat expected = response(kind, pair.dense, 1.0 / 1024, 400);
    const Mat got = response(kind, pair.sparse, 1.0 / 1024, 400);
    const double scale = expected.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 1e-6) << to_string(kind);
    EXPECT_LE((got - expected).cwiseAbs().maxCoeff(), 1e-10 * scale) << to_string(kind);
  }
}

// Free vibration in mode `mode` (1-based, kept): its modal coordinate q = phi^T M u decays as
// exp(-zeta omega t); the ratio is read from successive positive peaks (logarithmic decrement).
double measured_ratio(const StructuralModel& model, int mode, IntegratorKind kind) {
  const Modes modes = lowest_modes(model, mode);
  const Vec phi = modes.shapes.col(mode - 1);
  const double omega = modes.omega[mode - 1];
  // At least 200 steps a period, inside every explicit scheme's limit (omega_max dt <= 1 < 2).
  const double period = 2.0 * std::numbers::pi / omega;
  const double dt = std::min(period / 200, 1.0 / max_omega(model));
  const int steps = static_cast<int>(6 * period / dt);
  auto integrator = make_integrator(kind, model, dt);
  SparseLinearEvaluator evaluator(model.sparse_stiffness);
  const int n = model.dofs();
  const Vec zero = Vec::Zero(n);
  integrator->initialize(1e-3 * phi, zero, model.sparse_stiffness * (1e-3 * phi), zero);
  const Vec m_phi = model.sparse_mass * phi;
  std::vector<double> peaks;
  double before = 1e-3, now = 1e-3;
  for (int s = 0; s < steps && peaks.size() < 4; ++s) {
    integrator->step(zero, evaluator);
    const double next = m_phi.dot(integrator->displacement());
    if (s > 0 && now > before && now >= next) peaks.push_back(now);
    before = now;
    now = next;
  }
  if (peaks.size() < 4) return -1.0;
  const double delta = std::log(peaks.front() / peaks.back()) / (peaks.size() - 1);
  return delta / std::sqrt(4.0 * std::numbers::pi * std::numbers::pi + delta * delta);
}

TEST(SparseIntegrators, AKeptModeDecaysAtTheModalRatioInFreeVibration) {
  StructuralModel model = sparse_copy(dense_building(150));
  sparse_modal_damping(model, 0.05);
  for (int mode : {1, 5}) {
    for (IntegratorKind kind : {IntegratorKind::kExplicitNewmark, IntegratorKind::kKRAlpha}) {
      // 200 or more steps a period: the schemes' own error in the ratio is ~ (omega dt)^2 zeta.
      EXPECT_NEAR(measured_ratio(model, mode, kind), 0.05, 5e-4)
          << "mode " << mode << ", " << to_string(kind);
    }
  }
}

TEST(SparseIntegrators, DenseOnlySchemesRefuseAModelHeldSparseOnlyNamingTheLimit) {
  const StructuralModel model = sparse_copy(dense_building(20));
  for (IntegratorKind kind :
       {IntegratorKind::kExactZoh, IntegratorKind::kNewmarkAverageAcceleration}) {
    try {
      make_integrator(kind, model, 0.01);
      FAIL() << to_string(kind) << " took a sparse-only model";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("limit of 2000"), std::string::npos) << e.what();
    }
  }
}

TEST(SparseIntegrators, DenseOnlySchemesTakeAModelThatAlsoHoldsItsDenseMatrices) {
  StructuralModel model = dense_building(20);
  const StructuralModel sparse = sparse_copy(model);
  model.sparse_mass = sparse.sparse_mass;
  model.sparse_damping = sparse.sparse_damping;
  model.sparse_stiffness = sparse.sparse_stiffness;
  EXPECT_EQ(make_integrator(IntegratorKind::kExactZoh, model, 0.01)->kind(),
            IntegratorKind::kExactZoh);
}

TEST(SparseIntegrators, RefuseParametersOutOfRangeAsTheDenseOnesDo) {
  const StructuralModel model = sparse_copy(dense_building(10));
  IntegratorParameters bad;
  bad.alpha_os = 0.5;
  EXPECT_THROW(make_integrator(IntegratorKind::kAlphaOS, model, 0.01, bad), std::invalid_argument);
  bad = {};
  bad.rho_infinity = 1.5;
  EXPECT_THROW(make_integrator(IntegratorKind::kKRAlpha, model, 0.01, bad), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
