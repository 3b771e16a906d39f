#include "core/answer_replay.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/simulation.h"

namespace rths::core {
namespace {

constexpr double kDt = 0.002;

GroundMotion sine_motion(double seconds) {
  GroundMotion m{"sine", kDt, {}};
  for (int k = 0; k * kDt < seconds; ++k) m.acceleration.push_back(2.0 * std::sin(9.0 * k * kDt));
  return m;
}

HybridSetup shifted_sdof(double delay) {
  HybridSetup setup;
  setup.model = make_sdof(0.5, 0.05);
  setup.dt = kDt;
  setup.partition = partition_by_fraction(setup.model.storey_stiffness, 0.5, linear_factory());
  DelayChain chain;
  chain.add(std::make_unique<TimeShift>(delay, kDt));
  setup.delays.push_back(std::move(chain));
  return setup;
}

std::vector<std::int64_t> each_step_on(std::size_t steps, std::int64_t age) {
  std::vector<std::int64_t> used(steps);
  for (std::size_t k = 0; k < steps; ++k)
    used[k] = std::max<std::int64_t>(0, static_cast<std::int64_t>(k) - age);
  return used;
}

TEST(AnswerReplay, EveryStepOnItsOwnAnswerIsTheRunWithoutReplay) {
  const GroundMotion motion = sine_motion(2.0);
  AnswerSchedule fresh;
  fresh.actuator_used = {each_step_on(motion.acceleration.size(), 0)};
  fresh.storey_used = {each_step_on(motion.acceleration.size(), 0)};
  const SimulationResult plain = simulate(shifted_sdof(0.01), motion);
  const SimulationResult replayed = simulate(shifted_sdof(0.01), motion, {}, fresh);
  EXPECT_EQ(plain.displacement, replayed.displacement);
  EXPECT_EQ(fresh.late_steps(), 0u);
}

// A linear specimen answering one step late is the same actuator one step slower: the force used
// at step k is the one its shift gave command k - 1.
TEST(AnswerReplay, AnActuatorAlwaysOneStepLateIsItsShiftOneStepLonger) {
  const GroundMotion motion = sine_motion(3.0);
  AnswerSchedule late;
  late.actuator_used = {each_step_on(motion.acceleration.size(), 1)};
  const SimulationResult replayed = simulate(shifted_sdof(0.01), motion, {}, late);
  const SimulationResult slower = simulate(shifted_sdof(0.01 + kDt), motion);
  ASSERT_EQ(replayed.steps(), slower.steps());
  const double peak = slower.displacement.cwiseAbs().maxCoeff();
  EXPECT_GT(peak, 1e-3);
  EXPECT_LT((replayed.displacement - slower.displacement).cwiseAbs().maxCoeff(), 1e-12 * peak);
  EXPECT_LT((replayed.realised - slower.realised).cwiseAbs().maxCoeff(), 1e-12 * peak);
  EXPECT_EQ(late.late_steps(), motion.acceleration.size() - 1);  // step 1 on none: late too
}

TEST(AnswerReplay, EachSourceGetsTheOutputsOfTheStepItUsed) {
  AnswerSchedule schedule;
  schedule.storey_used = {{0, 1, 1, 3}};
  schedule.actuator_used = {{0, 0, 2, 2}};
  AnswerReplay replay(schedule, 1, 1, 4);
  Vec shear(1), realised(1), force(1);
  std::vector<double> shears, realiseds, forces;
  for (std::size_t k = 1; k < 4; ++k) {
    shear << 10.0 * static_cast<double>(k);
    realised << 0.1 * static_cast<double>(k);
    force << 100.0 * static_cast<double>(k);
    replay.step(k, shear, realised, force);
    shears.push_back(shear[0]);
    realiseds.push_back(realised[0]);
    forces.push_back(force[0]);
  }
  EXPECT_EQ(shears, (std::vector<double>{10.0, 10.0, 30.0}));
  EXPECT_EQ(realiseds, (std::vector<double>{0.0, 0.2, 0.2}));  // step 0: at rest
  EXPECT_EQ(forces, (std::vector<double>{0.0, 200.0, 200.0}));
  EXPECT_EQ(schedule.late_steps(), 3u);  // 1 and 3 (actuator), 2 (storey)
}

TEST(AnswerReplay, AnAnswerToACommandNotYetSentIsRefusedNamingItsSource) {
  AnswerSchedule schedule;
  schedule.actuator_used = {{0, 2, 2}};
  AnswerReplay replay(schedule, 1, 1, 3);
  Vec shear = Vec::Zero(1), realised = Vec::Zero(1), force = Vec::Zero(1);
  try {
    replay.step(1, shear, realised, force);
    FAIL() << "an answer from the future was replayed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("actuator 1 at step 1 uses the answer to step 2"),
              std::string::npos)
        << e.what();
  }
}

TEST(AnswerReplay, AScheduleShorterThanTheRunIsRefused) {
  AnswerSchedule schedule;
  schedule.actuator_used = {{0, 1}};
  EXPECT_THROW(AnswerReplay(schedule, 1, 1, 5), std::invalid_argument);
}

TEST(AnswerReplay, AnImplicitIntegratorCannotReplay) {
  const GroundMotion motion = sine_motion(0.5);
  HybridSetup setup = shifted_sdof(0.0);
  setup.delays.clear();
  setup.integrator = IntegratorKind::kNewmarkAverageAcceleration;
  AnswerSchedule schedule;
  schedule.actuator_used = {each_step_on(motion.acceleration.size(), 1)};
  EXPECT_THROW(simulate(setup, motion, {}, schedule), std::invalid_argument);
}

}  // namespace
}  // namespace rths::core
