#include "core/sparse_integrators.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

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
  const StructuralModel model = sparse_copy(dense_building(300));
  SparseLinearEvaluator evaluator(model.sparse_stiffness);
  const Vec load = Vec::Constant(model.dofs(), 1e3);
  for (IntegratorKind kind : kSparseKinds) {
    auto integrator = make_integrator(kind, model, 1.0 / 1024);
    integrator->initialize(Vec::Zero(300), Vec::Zero(300), Vec::Zero(300), load);
    const long before = allocations.load();
    for (int s = 0; s < 50; ++s) integrator->step(load, evaluator);
    EXPECT_EQ(allocations.load() - before, 0) << to_string(kind);
    EXPECT_TRUE(integrator->displacement().allFinite());
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
