#include "core/substructure.h"

#include <gtest/gtest.h>

namespace rths::core {
namespace {

TEST(StoreyAssemblyTest, DriftsForcesAndTangentAreConsistent) {
  const StoreyAssembly assembly(3);
  Vec u(3), drift(3), force(3);
  u << 1.0, 3.0, 6.0;
  assembly.drifts(u, drift);
  EXPECT_TRUE(drift.isApprox(Vec::LinSpaced(3, 1.0, 3.0)));
  Vec shear(3);
  shear << 10.0, 20.0, 30.0;
  assembly.dof_forces(shear, force);
  Vec expected(3);
  expected << -10.0, -10.0, 30.0;
  EXPECT_TRUE(force.isApprox(expected));
  // B^T diag(k) B u must equal the forces of linear storeys with those stiffnesses.
  Mat k;
  assembly.tangent(Vec::Constant(3, 2.0), k);
  Vec linear_force(3);
  assembly.dof_forces(2.0 * drift, linear_force);
  EXPECT_TRUE((k * u).isApprox(linear_force));
}

TEST(PartitionTest, FractionSplitsEveryStoreyAndPlacesOneActuatorEach) {
  const HybridPartition p = partition_by_fraction({100.0, 50.0}, 0.25, linear_factory());
  ASSERT_EQ(p.actuator_storeys, (std::vector<int>{0, 1}));
  EXPECT_DOUBLE_EQ(p.numerical[0]->initial_stiffness(), 75.0);
  EXPECT_DOUBLE_EQ(p.experimental[1]->initial_stiffness(), 12.5);
  const HybridPartition all = partition_by_fraction({100.0}, 1.0, linear_factory());
  EXPECT_EQ(all.numerical[0], nullptr);
  const HybridPartition none = partition_by_fraction({100.0}, 0.0, linear_factory());
  EXPECT_TRUE(none.actuator_storeys.empty());
  EXPECT_THROW(partition_by_fraction({100.0}, 1.5, linear_factory()), std::invalid_argument);
}

TEST(PartitionTest, WholeStoreysAreExperimentalAndBadStoreysAreNamed) {
  const HybridPartition p = partition_by_storeys({100.0, 50.0, 25.0}, {1}, linear_factory());
  EXPECT_EQ(p.actuator_storeys, (std::vector<int>{1}));
  EXPECT_EQ(p.numerical[1], nullptr);
  EXPECT_NE(p.numerical[0], nullptr);
  try {
    partition_by_storeys({100.0}, {3}, linear_factory());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("storey 4"), std::string::npos);
  }
  EXPECT_THROW(partition_by_storeys({100.0, 1.0}, {0, 0}, linear_factory()), std::invalid_argument);
}

TEST(PartitionTest, CopiesAreIndependent) {
  HybridPartition a = partition_by_fraction({100.0}, 0.5, [](double k) {
    return std::make_unique<BilinearKinematic>(k, 0.01, 0.1);
  });
  HybridPartition b = a;
  a.experimental[0]->step(0.05);  // yields a's copy only
  EXPECT_DOUBLE_EQ(b.experimental[0]->trial(0.001).force, 50.0 * 0.001);
}

TEST(HybridRestoringTest, DelayedActuatorSeesTheShiftedCommandAndAddsItsForce) {
  constexpr double kDt = 0.01;
  const HybridPartition p = partition_by_fraction({100.0}, 0.5, linear_factory());
  std::vector<DelayChain> chains(1);
  chains[0].add(std::make_unique<TimeShift>(2 * kDt, kDt));
  HybridRestoring restoring(p, std::move(chains), kDt);
  EXPECT_FALSE(restoring.repeatable());
  const std::vector<double> commands = {0.0, 1.0, 2.0, 3.0};
  for (std::size_t k = 0; k < commands.size(); ++k) {
    restoring.set_time(static_cast<double>(k) * kDt);
    const Vec& r = restoring.trial(Vec::Constant(1, commands[k]), Vec::Zero(1), nullptr);
    restoring.commit();
    const double realised = k >= 2 ? commands[k - 2] : 0.0;
    EXPECT_DOUBLE_EQ(restoring.realised()(0), realised) << k;
    EXPECT_DOUBLE_EQ(r(0), 50.0 * commands[k] + 50.0 * realised) << k;
  }
}

TEST(HybridRestoringTest, UndelayedPartitionIsRepeatableWithAFullTangent) {
  const HybridPartition p = partition_by_fraction({100.0, 40.0}, 0.5, linear_factory());
  HybridRestoring restoring(p, {}, 0.01);
  EXPECT_TRUE(restoring.repeatable());
  Mat tangent;
  Vec u(2);
  u << 0.1, 0.3;
  const Vec r = restoring.trial(u, Vec::Zero(2), &tangent);
  const StructuralModel model = make_shear_building({1.0, 1.0}, {100.0, 40.0});
  EXPECT_TRUE(tangent.isApprox(model.stiffness));
  EXPECT_TRUE(r.isApprox(model.stiffness * u));
}

TEST(HybridRestoringTest, WrongNumberOfChainsIsRefused) {
  const HybridPartition p = partition_by_fraction({100.0, 40.0}, 0.5, linear_factory());
  EXPECT_THROW(HybridRestoring(p, std::vector<DelayChain>(3), 0.01), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
