// The SIMD batch kernel against core::simulate with the same setup (explicit Newmark, SDOF,
// linear, time shift): the histories must agree to round-off, lane by lane.
#include "analysis/sweep/batch_kernel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/ground_motion.h"
#include "core/metrics.h"
#include "core/simulation.h"
#include "core/structure.h"
#include "core/substructure.h"
#include "study/motion_files.h"
#include "study/study.h"

namespace rths::analysis {
namespace {

constexpr double kDt = 0.002;
constexpr double kZeta = 0.05;
// Round-off over a few thousand steps, relative to the peak response.
constexpr double kRelativeTolerance = 1e-10;

core::GroundMotion test_motion() {
  core::GroundMotion record =
      study::read_at2(std::string(RTHS_DATA_DIR) + "/ground_motions/elcentro_1940_ns_peknold.AT2");
  return core::truncated(core::resampled(record, kDt), 8.0);
}

struct CoreRun {
  std::vector<double> u;
  bool diverged;
};

CoreRun run_core(double period, double mass, double alpha, double delay,
                 const core::GroundMotion& motion) {
  core::HybridSetup setup;
  setup.model = core::make_sdof(period, kZeta, mass);
  setup.integrator = core::IntegratorKind::kExplicitNewmark;
  setup.dt = kDt;
  setup.partition =
      core::partition_by_fraction(setup.model.storey_stiffness, alpha, core::linear_factory());
  if (delay > 0 && alpha > 0) {
    core::DelayChain chain;
    chain.add(std::make_unique<core::TimeShift>(delay, kDt));
    setup.delays.push_back(std::move(chain));
  }
  const core::SimulationResult result = core::simulate(setup, motion);
  CoreRun run{std::vector<double>(static_cast<std::size_t>(result.displacement.rows())),
              result.diverged};
  for (std::size_t i = 0; i < run.u.size(); ++i)
    run.u[i] = result.displacement(static_cast<Eigen::Index>(i), 0);
  return run;
}

SdofLane lane_for(double period, double mass, double alpha) {
  const core::StructuralModel model = core::make_sdof(period, kZeta, mass);
  const double k = model.storey_stiffness[0];
  return {model.mass(0, 0), model.damping(0, 0), alpha < 1 ? (1 - alpha) * k : 0.0,
          alpha > 0 ? alpha * k : 0.0};
}

struct KernelCase {
  double delay;  // s
  double alpha;
};

class KernelMatchesCore : public ::testing::TestWithParam<KernelCase> {};

TEST_P(KernelMatchesCore, HistoriesAgreeToRoundOff) {
  const core::GroundMotion motion = test_motion();
  const KernelCase c = GetParam();
  // 19 lanes: more than two AVX-512 vectors and not a multiple of 8, so padding is exercised.
  std::vector<double> periods;
  for (int i = 0; i < 19; ++i) periods.push_back(0.08 + 0.15 * i);
  std::vector<SdofLane> lanes;
  for (double T : periods) lanes.push_back(lane_for(T, 3.0, c.alpha));
  std::vector<std::vector<double>> histories;
  const auto outcomes =
      run_linear_sdof_lanes(lanes, motion.acceleration, kDt, c.delay, {}, &histories);
  ASSERT_EQ(outcomes.size(), periods.size());
  std::size_t stable_lanes = 0;
  for (std::size_t l = 0; l < periods.size(); ++l) {
    const CoreRun expected = run_core(periods[l], 3.0, c.alpha, c.delay, motion);
    EXPECT_EQ(outcomes[l].diverged, expected.diverged) << "period " << periods[l];
    // core stops at the first step beyond the bound; compare up to there.
    ASSERT_GE(histories[l].size(), expected.u.size()) << "lane " << l;
    const std::vector<double> kernel(
        histories[l].begin(),
        histories[l].begin() + static_cast<std::ptrdiff_t>(expected.u.size()));
    const double peak = core::peak_abs(expected.u);
    ASSERT_GT(peak, 0.0);
    EXPECT_LE(core::peak_error(expected.u, kernel), kRelativeTolerance * peak)
        << "period " << periods[l] << " delay " << c.delay << " alpha " << c.alpha;
    if (!expected.diverged) {
      ++stable_lanes;
      EXPECT_EQ(histories[l].size(), expected.u.size());
      EXPECT_NEAR(outcomes[l].peak_abs, peak, kRelativeTolerance * peak);
    }
  }
  EXPECT_GE(stable_lanes, periods.size() / 2);  // the comparison is mostly of stable runs
}

INSTANTIATE_TEST_SUITE_P(Delays, KernelMatchesCore,
                         ::testing::Values(KernelCase{0.0, 1.0},      // no delay
                                           KernelCase{0.014, 1.0},    // 7 whole steps
                                           KernelCase{0.0151, 0.6},   // 7.55 steps, split storey
                                           KernelCase{0.0007, 1.0},   // less than one step
                                           KernelCase{0.018, 0.0}));  // nothing experimental

TEST(LinearSdofBatch, LanesDoNotDependOnTheirNeighbours) {
  const core::GroundMotion motion = test_motion();
  const std::vector<SdofLane> many = {lane_for(0.3, 1, 1), lane_for(0.9, 1, 1),
                                      lane_for(2.0, 1, 1)};
  const auto together = run_linear_sdof_lanes(many, motion.acceleration, kDt, 0.01);
  for (std::size_t l = 0; l < many.size(); ++l) {
    const auto alone =
        run_linear_sdof_lanes(std::span(&many[l], 1), motion.acceleration, kDt, 0.01);
    EXPECT_EQ(alone[0].peak_abs, together[l].peak_abs);  // bit for bit
  }
}

TEST(LinearSdofBatch, FeedingInPiecesEqualsOneGo) {
  const core::GroundMotion motion = test_motion();
  const std::vector<SdofLane> lanes = {lane_for(0.5, 1, 1), lane_for(1.5, 1, 0.5)};
  LinearSdofBatch whole(lanes, kDt, 0.013), pieces(lanes, kDt, 0.013);
  whole.start(motion.acceleration[0]);
  pieces.start(motion.acceleration[0]);
  const std::span<const double> rest(motion.acceleration.data() + 1,
                                     motion.acceleration.size() - 1);
  whole.advance(rest, nullptr);
  pieces.advance(rest.first(1000), nullptr);
  pieces.advance(rest.subspan(1000), nullptr);
  for (int l = 0; l < 2; ++l)
    EXPECT_EQ(whole.outcomes()[l].peak_abs, pieces.outcomes()[l].peak_abs);
}

TEST(LinearSdofBatch, FlagsDivergenceBeyondTheCriticalDelay) {
  const core::GroundMotion motion = test_motion();
  // T = 0.1 s with zeta = 5 %: the critical shift is a few ms; 40 ms is far beyond it.
  const std::vector<SdofLane> lanes = {lane_for(0.1, 1, 1), lane_for(2.5, 1, 1)};
  const auto outcomes = run_linear_sdof_lanes(lanes, motion.acceleration, kDt, 0.04);
  EXPECT_TRUE(outcomes[0].diverged);
  EXPECT_FALSE(outcomes[1].diverged);
  EXPECT_TRUE(core::simulate(
                  [&] {
                    core::HybridSetup setup;
                    setup.model = core::make_sdof(0.1, kZeta, 1.0);
                    setup.dt = kDt;
                    setup.partition = core::partition_by_fraction(setup.model.storey_stiffness, 1.0,
                                                                  core::linear_factory());
                    core::DelayChain chain;
                    chain.add(std::make_unique<core::TimeShift>(0.04, kDt));
                    setup.delays.push_back(std::move(chain));
                    return setup;
                  }(),
                  motion)
                  .diverged);
}

TEST(LinearSdofBatch, RejectsBadInput) {
  const std::vector<SdofLane> one = {lane_for(0.5, 1, 1)};
  EXPECT_THROW(LinearSdofBatch(one, 0.0, 0.01), std::invalid_argument);
  EXPECT_THROW(LinearSdofBatch(one, 0.01, -0.01), std::invalid_argument);
  EXPECT_THROW(LinearSdofBatch(std::span<const SdofLane>(), 0.01, 0.0), std::invalid_argument);
  std::vector<SdofLane> too_many(LinearSdofBatch::kMaxLanes + 1, one[0]);
  EXPECT_THROW(LinearSdofBatch(too_many, 0.01, 0.0), std::invalid_argument);
  SdofLane massless = one[0];
  massless.mass = 0.0;
  EXPECT_THROW(LinearSdofBatch(std::span(&massless, 1), 0.01, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace rths::analysis
