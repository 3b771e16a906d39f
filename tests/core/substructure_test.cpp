#include "core/substructure.h"

#include <gtest/gtest.h>

#include <cmath>

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

TEST(StoreyAssemblyTest, ByDofsIsTheIdentity) {
  const StoreyAssembly assembly(3, true);
  Vec u(3), drift(3), force(3);
  u << 1.0, 3.0, 6.0;
  assembly.drifts(u, drift);
  EXPECT_EQ(drift, u);
  assembly.dof_forces(u, force);
  EXPECT_EQ(force, u);
  Mat k;
  assembly.tangent(u, k);
  EXPECT_EQ(k, Mat(u.asDiagonal()));
}

TEST(PartitionTest, ByDofsTakesEachSpecimenOutOfTheStiffnessMatrix) {
  Mat k(3, 3);
  k << 4, -2, 0, -2, 4, -2, 0, -2, 2;
  std::vector<DofSpecimen> specimens;
  specimens.push_back({2, std::make_unique<LinearSpring>(1.5)});
  const HybridPartition p = partition_by_dofs(k, std::move(specimens));
  EXPECT_EQ(p.actuator_storeys, std::vector<int>{2});
  EXPECT_EQ(p.numerical_matrix.coeff(2, 2), 0.5);
  EXPECT_TRUE(p.has_numerical(0) && p.has_numerical(2));
  // DOF 1 couples to DOF 2 only; DOF 2 to all three.
  EXPECT_EQ(p.coupled_to({0}), (std::vector<int>{0, 1}));
  EXPECT_EQ(p.coupled_to({1}), (std::vector<int>{0, 1, 2}));
  // The numerical part: K_N u, row by row; a copy carries the matrix.
  NumericalSubstructure numerical(p);
  const NumericalSubstructure copy(numerical);
  EXPECT_EQ(Mat(copy.matrix()), Mat(p.numerical_matrix));
  Vec u(3), shear(3);
  u << 1.0, 2.0, 3.0;
  numerical.trial(u, shear, nullptr);
  EXPECT_EQ(shear, Mat(p.numerical_matrix) * u);
  std::vector<DofSpecimen> too_stiff;
  too_stiff.push_back({0, std::make_unique<LinearSpring>(5.0)});
  EXPECT_THROW(partition_by_dofs(k, std::move(too_stiff)), std::invalid_argument);
}

TEST(StoreyAssemblyTest, ElementRowsFollowTheDofsAndAssembleByTheSameRow) {
  // 3 DOFs and two elements: the storey between DOFs 1 and 2, a brace 0.5 (u3 - u2).
  const StoreyAssembly assembly(3, true, {{{{1, 1.0}, {0, -1.0}}}, {{{2, 0.5}, {1, -0.5}}}});
  ASSERT_EQ(assembly.storeys(), 5);
  ASSERT_EQ(assembly.dofs(), 3);
  Vec u(3), drift = Vec::Zero(5), force = Vec::Zero(3);
  u << 0.1, 0.3, 0.7;
  assembly.drifts(u, drift);
  EXPECT_DOUBLE_EQ(drift[3], 0.2);
  EXPECT_DOUBLE_EQ(drift[4], 0.2);
  Vec shear(5);
  shear << 1.0, 2.0, 3.0, 10.0, 20.0;
  assembly.dof_forces(shear, force);
  EXPECT_DOUBLE_EQ(force[0], 1.0 - 10.0);
  EXPECT_DOUBLE_EQ(force[1], 2.0 + 10.0 - 10.0);
  EXPECT_DOUBLE_EQ(force[2], 3.0 + 10.0);
  // The tangent is B' diag(k) B, and the virtual work of the forces is that of the channels.
  Vec k(5);
  k << 0.0, 0.0, 0.0, 4.0, 8.0;
  Mat tangent;
  assembly.tangent(k, tangent);
  Mat b = Mat::Zero(5, 3);
  b.topRows(3).setIdentity();
  b.row(3) << -1.0, 1.0, 0.0;
  b.row(4) << 0.0, -0.5, 0.5;
  EXPECT_LE((tangent - b.transpose() * k.asDiagonal() * b).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(force.dot(u), shear.dot(drift), 1e-12);
}

TEST(PartitionTest, AnElementBetweenDofsTakesItsStiffnessOutAlongItsRow) {
  Mat k(3, 3);
  k << 4.0, -2.0, 0.0, -2.0, 3.5, -1.5, 0.0, -1.5, 1.5;
  std::vector<DofSpecimen> specimens;
  specimens.push_back({0, std::make_unique<LinearSpring>(0.5), {{{1, 1.0}, {0, -1.0}}}});
  specimens.push_back({2, std::make_unique<LinearSpring>(0.25), {}});
  const HybridPartition p = partition_by_dofs(k, std::move(specimens));
  // The grounded specimen keeps its DOF's channel; the element comes after the DOFs.
  EXPECT_EQ(p.actuator_storeys, (std::vector<int>{2, 3}));
  EXPECT_EQ(p.channels(), 4);
  EXPECT_EQ(p.dofs(), 3);
  EXPECT_EQ(p.channel_name(3), "element 1 (DOF 2 - DOF 1)");
  EXPECT_EQ(p.channel_name(1), "DOF 2");
  EXPECT_FALSE(p.has_numerical(3));
  EXPECT_DOUBLE_EQ(p.numerical_matrix.coeff(0, 0), 3.5);
  EXPECT_DOUBLE_EQ(p.numerical_matrix.coeff(0, 1), -1.5);
  EXPECT_DOUBLE_EQ(p.numerical_matrix.coeff(1, 1), 3.0);
  EXPECT_DOUBLE_EQ(p.numerical_matrix.coeff(2, 2), 1.25);
  // K_N + K_e is K again.
  EXPECT_LE((Mat(p.numerical_matrix) + p.experimental_stiffness() - k).cwiseAbs().maxCoeff(),
            1e-15);
  const HybridPartition copy(p);
  EXPECT_EQ(copy.elements.size(), 1u);
}

TEST(PartitionTest, AnElementStifferThanWhatItReplacesIsRefused) {
  Mat k(2, 2);
  k << 4.0, -2.0, -2.0, 2.0;  // storeys 2 and 2
  std::vector<DofSpecimen> too_stiff;
  too_stiff.push_back({0, std::make_unique<LinearSpring>(2.5), {{{1, 1.0}, {0, -1.0}}}});
  try {
    partition_by_dofs(k, std::move(too_stiff));
    FAIL() << "an element stiffer than its storey was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stiffer than the structure"), std::string::npos)
        << e.what();
  }
  std::vector<DofSpecimen> outside;
  outside.push_back({0, std::make_unique<LinearSpring>(1.0), {{{5, 1.0}}}});
  EXPECT_THROW(partition_by_dofs(k, std::move(outside)), std::invalid_argument);
  std::vector<DofSpecimen> whole;
  whole.push_back({0, std::make_unique<LinearSpring>(2.0), {{{1, 1.0}, {0, -1.0}}}});
  EXPECT_NO_THROW(partition_by_dofs(k, std::move(whole)));
}

TEST(HybridRestoringTest, AnElementsForceEntersBothOfItsDofs) {
  Mat k(2, 2);
  k << 4.0, -2.0, -2.0, 2.0;
  std::vector<DofSpecimen> specimens;
  specimens.push_back({0, std::make_unique<LinearSpring>(2.0), {{{1, 1.0}, {0, -1.0}}}});
  HybridRestoring restoring(partition_by_dofs(k, std::move(specimens)), {}, 0.01);
  Vec u(2), v = Vec::Zero(2);
  u << 0.1, 0.4;
  const Vec& force = restoring.trial(u, v, nullptr);
  ASSERT_EQ(force.size(), 2);
  EXPECT_NEAR(force[0], (k * u)[0], 1e-15);
  EXPECT_NEAR(force[1], (k * u)[1], 1e-15);
  EXPECT_DOUBLE_EQ(restoring.command()[0], 0.3);
  EXPECT_DOUBLE_EQ(restoring.measured_force()[0], 0.6);
}

// K_N held sparse: each row's stored entries summed in column order equal the dense row's
// sequential dot product bit for bit (its zero terms add nothing), so in-process and distributed
// runs, and runs made before K_N was sparse, agree.
TEST(PartitionTest, SparseRowSumsEqualTheDenseRowDotProducts) {
  const int n = 40;
  Mat k = Mat::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    k(i, i) = 3.0 + std::sin(i);
    if (i + 1 < n) k(i, i + 1) = k(i + 1, i) = -1.0 / (1.0 + i);
    if (i + 7 < n) k(i, i + 7) = k(i + 7, i) = 0.1 * std::cos(i);
  }
  const HybridPartition p = partition_by_dofs(k, {});
  EXPECT_EQ(p.numerical_matrix.nonZeros(), (k.array() != 0.0).count());
  NumericalSubstructure numerical(p);
  Vec u(n), shear(n);
  for (int i = 0; i < n; ++i) u[i] = std::exp(0.1 * i) * (i % 2 ? -1.0 : 1.0) / 3.0;
  numerical.trial(u, shear, nullptr);
  for (int i = 0; i < n; ++i) EXPECT_EQ(shear[i], k.row(i).dot(u)) << "row " << i;
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
  HybridPartition a = partition_by_fraction(
      {100.0}, 0.5, [](double k) { return std::make_unique<BilinearKinematic>(k, 0.01, 0.1); });
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

Actuator undelayed_spring(double k) {
  return Actuator(DelayChain{}, std::make_unique<LinearSpring>(k));
}

TEST(ActuatorServoTest, OneServoPeriodPerStepActsOnTheCommandItself) {
  DelayChain chain;
  chain.add(std::make_unique<FirstOrderActuator>(0.01, 0.001));
  Actuator plain(chain, std::make_unique<LinearSpring>(2.0e5));
  Actuator servo(chain, std::make_unique<LinearSpring>(2.0e5));
  servo.set_servo(1, 0.001);
  for (int k = 1; k <= 50; ++k) {
    const CommandSample c{0.001 * k, 0.003 * std::sin(0.2 * k) + 1e-4 / 3.0, 0.1};
    const ActuatorOutput a = plain.step(c), b = servo.step(c);
    ASSERT_EQ(a.realised, b.realised) << k;  // bit for bit, no interpolation round-off
    ASSERT_EQ(a.force, b.force) << k;
  }
}

TEST(ActuatorServoTest, EachCommandIsRampedOverTheServoPeriodsOfOneStep) {
  Actuator actuator = undelayed_spring(1000.0);
  actuator.set_servo(4, 0.00025);
  actuator.command({0.001, 0.004, 0.0});
  std::vector<double> seen;
  for (int j = 0; j < 4; ++j) seen.push_back(actuator.tick().realised);
  EXPECT_DOUBLE_EQ(seen[0], 0.001);
  EXPECT_DOUBLE_EQ(seen[1], 0.002);
  EXPECT_DOUBLE_EQ(seen[2], 0.003);
  EXPECT_EQ(seen[3], 0.004);  // the command itself at the end of its step
  // Past the ramp the servo holds the target (a real-time loop keeps ticking).
  const ActuatorOutput held = actuator.tick();
  EXPECT_EQ(held.realised, 0.004);
  EXPECT_DOUBLE_EQ(held.force, 4.0);
  // step() is command() then the step's servo periods.
  EXPECT_EQ(actuator.step({0.002, 0.0, 0.0}).realised, 0.0);
}

TEST(ActuatorServoTest, ACommandArrivingMidRampStartsFromWhereTheServoIsWithoutAJump) {
  Actuator actuator = undelayed_spring(1000.0);
  actuator.set_servo(4, 0.00025);
  actuator.command({0.001, 0.004, 0.0});
  actuator.tick();  // 0.001
  actuator.tick();  // 0.002
  actuator.command({0.002, 0.010, 0.0});
  EXPECT_DOUBLE_EQ(actuator.tick().realised, 0.002 + 0.008 / 4);
  EXPECT_EQ(actuator.ticks_since_command(), 1);
}

TEST(ActuatorServoTest, FasterServoWithAFirstOrderLagConvergesToTheContinuousResponse) {
  // tau du/dt = u_c - u with a ramp input u_c = r t: u(t) = r (t - tau (1 - exp(-t / tau))).
  constexpr double kTau = 0.01, kRate = 0.5, kDt = 0.001;
  const auto error_with = [&](int substeps) {
    DelayChain chain;
    chain.add(std::make_unique<FirstOrderActuator>(kTau, kDt / substeps));
    Actuator actuator(chain, std::make_unique<LinearSpring>(1.0));
    actuator.set_servo(substeps, kDt / substeps);
    double worst = 0.0;
    for (int k = 1; k <= 100; ++k) {
      const double t = kDt * k;
      const double exact = kRate * (t - kTau * (1 - std::exp(-t / kTau)));
      worst = std::max(worst, std::abs(actuator.step({t, kRate * t, kRate}).realised - exact));
    }
    return worst;
  };
  EXPECT_LT(error_with(8), 0.5 * error_with(1));
}

TEST(ActuatorServoTest, HoldRampsTheTargetFromWhereItIsAtMostMaxChangePerTickThenStays) {
  Actuator actuator = undelayed_spring(1000.0);
  actuator.set_servo(4, 0.00025);
  actuator.command({0.001, 0.004, 0.0});
  actuator.tick();  // target 1 mm, mid-ramp
  actuator.tick();  // 2 mm
  actuator.hold(-0.001, 0.0012);
  EXPECT_TRUE(actuator.holding());
  EXPECT_DOUBLE_EQ(actuator.target_displacement(), 0.002);  // starts where the servo is
  EXPECT_NEAR(actuator.tick().realised, 0.0008, 1e-15);
  EXPECT_NEAR(actuator.tick().realised, -0.0004, 1e-15);
  EXPECT_FALSE(actuator.hold_reached());
  EXPECT_EQ(actuator.tick().realised, -0.001);  // lands exactly, 0.6 mm < 1.2 mm left
  EXPECT_TRUE(actuator.hold_reached());
  EXPECT_EQ(actuator.tick().realised, -0.001);  // and stays
  EXPECT_THROW(actuator.hold(0.0, 0.0), std::invalid_argument);
}

TEST(ActuatorServoTest, ACopyKeepsItsServoAndRampState) {
  Actuator actuator = undelayed_spring(1000.0);
  actuator.set_servo(4, 0.00025);
  actuator.command({0.001, 0.004, 0.0});
  actuator.tick();
  Actuator copy(actuator);
  EXPECT_EQ(copy.servo_substeps(), 4);
  EXPECT_EQ(copy.tick().realised, actuator.tick().realised);
}

TEST(ActuatorServoTest, BadServoSettingsAreRefused) {
  Actuator actuator = undelayed_spring(1.0);
  EXPECT_THROW(actuator.set_servo(0, 0.001), std::invalid_argument);
  EXPECT_THROW(actuator.set_servo(4, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
