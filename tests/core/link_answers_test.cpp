#include "core/link_answers.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/simulation.h"

namespace rths::core {
namespace {

constexpr double kDt = 0.001;

LinkModel symmetric_link(double one_way, double jitter = 0.0, double loss = 0.0) {
  LinkModel link;
  for (LinkWay* way : {&link.to_node, &link.from_node}) {
    way->one_way_delay = one_way;
    way->jitter = jitter;
    way->loss = loss;
  }
  link.to_node.seed = 11;
  link.from_node.seed = 12;
  return link;
}

GroundMotion sine_motion(double seconds) {
  GroundMotion m{"sine", kDt, {}};
  for (int k = 0; k * kDt < seconds; ++k) m.acceleration.push_back(2.0 * std::sin(9.0 * k * kDt));
  return m;
}

// SDOF, T = 0.5 s, half its stiffness behind one actuator whose command is shifted by `shift`.
HybridSetup sdof_behind(double shift) {
  HybridSetup setup;
  setup.model = make_sdof(0.5, 0.05);
  setup.dt = kDt;
  setup.partition = partition_by_fraction(setup.model.storey_stiffness, 0.3, linear_factory());
  DelayChain chain;
  if (shift > 0) chain.add(std::make_unique<TimeShift>(shift, kDt));
  setup.delays.push_back(std::move(chain));
  return setup;
}

TEST(LinkAnswers, AFixedRoundTripUsesTheAnswerThatManyStepsOld) {
  const std::vector<std::int64_t> used = link_answer_steps(symmetric_link(0.030), kDt, 500);
  for (std::size_t k = 0; k < used.size(); ++k)
    EXPECT_EQ(used[k], std::max<std::int64_t>(0, static_cast<std::int64_t>(k) - 60)) << k;
  const LinkAnswerStats stats = link_answer_stats(used);
  EXPECT_EQ(stats.max_age, 60);
  EXPECT_EQ(stats.median_age, 60);
  EXPECT_EQ(stats.used_answers, 500u - 61u);  // steps 61..499 use answers 1..439
  EXPECT_EQ(stats.repeated_steps, 0u);
  EXPECT_EQ(stats.unused_answers, 0u);
}

TEST(LinkAnswers, WithoutLagEveryStepUsesItsOwnAnswer) {
  const std::vector<std::int64_t> used = link_answer_steps(LinkModel{}, kDt, 100);
  for (std::size_t k = 0; k < used.size(); ++k) EXPECT_EQ(used[k], static_cast<std::int64_t>(k));
}

// The specimen is time-invariant: answering 60 steps late is the same as seeing the command 60 ms
// late, so the link and a 60 ms shift on the command give one response.
TEST(LinkAnswers, AFixedLinkIsTheShiftOfItsRoundTripOnTheCommand) {
  const GroundMotion motion = sine_motion(3.0);
  HybridSetup linked = sdof_behind(0.0);
  linked.links = {symmetric_link(0.030)};
  const SimulationResult over_link = simulate(linked, motion);
  const SimulationResult shifted = simulate(sdof_behind(0.060), motion);
  ASSERT_EQ(over_link.steps(), shifted.steps());
  const double peak = shifted.displacement.cwiseAbs().maxCoeff();
  EXPECT_GT(peak, 1e-3);
  EXPECT_LT((over_link.displacement - shifted.displacement).cwiseAbs().maxCoeff(), 1e-12 * peak);
}

// Loss p each way loses 1 - (1 - p)^2 of the answers. Jitter on a FIFO way (a message waits for
// the one before) releases answers in bursts: several arrive within one step, only the newest
// is used, and the step after a burst reuses it. So the answers used are fewer than those that
// arrive and their age is the round trip or more, never less, up to the round trip + 6 jitter
// each way (the normal draws are not capped; 6 sd is past any of 2 x 20,000 draws here).
TEST(LinkAnswers, JitterAndLossLoseAndDelayAnswersAsTheirDrawsSay) {
  const std::size_t steps = 20000;
  const std::vector<std::int64_t> used =
      link_answer_steps(symmetric_link(0.030, 0.0025, 0.05), kDt, steps);
  const LinkAnswerStats stats = link_answer_stats(used);
  const double unused = static_cast<double>(stats.unused_answers) / static_cast<double>(steps);
  EXPECT_GT(unused, 1.0 - 0.95 * 0.95);
  EXPECT_LT(unused, 0.95);
  EXPECT_GT(stats.repeated_steps, steps / 20);
  // Every answer up to the last one used is either used or not.
  EXPECT_EQ(stats.used_answers + stats.unused_answers, static_cast<std::size_t>(used.back()));
  EXPECT_GE(stats.median_age, 60);
  EXPECT_LE(stats.max_age, 60 + 2 * 6 * 3 + 1);
  for (std::size_t k = 1; k < steps; ++k) ASSERT_GE(used[k], used[k - 1]) << k;
  EXPECT_EQ(used, link_answer_steps(symmetric_link(0.030, 0.0025, 0.05), kDt, steps));
  const LinkAnswerStats lossless =
      link_answer_stats(link_answer_steps(symmetric_link(0.030, 0.0025), kDt, steps));
  EXPECT_LT(lossless.unused_answers, stats.unused_answers);
  EXPECT_GT(lossless.unused_answers, 0u);  // the bursts alone
}

TEST(LinkAnswers, DriftLengthensTheRoundTripWithTime) {
  LinkModel link = symmetric_link(0.010);
  link.to_node.drift_rate = link.from_node.drift_rate = 0.002;  // 2 ms per s each way
  const std::vector<std::int64_t> used = link_answer_steps(link, kDt, 10001);
  EXPECT_EQ(1000 - used[1000], 20 + 4);  // 10 ms + 2 ms each way at t = 1 s
  EXPECT_NEAR(static_cast<double>(10000 - used[10000]), 20 + 40 / (1 - 0.004), 1.0);
}

TEST(LinkAnswers, DroppedStepsAreNeverUsed) {
  LinkModel link = symmetric_link(0.002);
  link.to_node.drop_first_step = 100;
  link.to_node.drop_steps = 50;
  const std::vector<std::int64_t> used = link_answer_steps(link, kDt, 400);
  for (std::size_t k = 0; k < used.size(); ++k) {
    EXPECT_FALSE(used[k] >= 100 && used[k] < 150) << k;
  }
  EXPECT_EQ(used[150], 99);  // the integrator keeps the last answer through the burst
  EXPECT_EQ(link_answer_stats(used).unused_answers, 50u);
}

TEST(LinkAnswers, AnImplicitIntegratorIsRefusedNamingTheLink) {
  HybridSetup setup = sdof_behind(0.0);
  setup.integrator = IntegratorKind::kNewmarkAverageAcceleration;
  setup.links = {symmetric_link(0.01)};
  try {
    simulate(setup, sine_motion(0.1));
    FAIL() << "an implicit integrator ran over a link";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a case's link"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rths::core
