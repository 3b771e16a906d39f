// The force predictor (core/force_predictor.h) over Cyclone DDS: the coordinator applies the same
// blocks to the emulator's answers as core::simulate applies in process, so a lockstep run of a
// case with a predictor equals the in-process run bit for bit, and the record's link samples
// carry the prediction error of every step. Real processes on loopback, on the
// shared DDS domain, each test on topics of its own.
#include <gtest/gtest.h>

#include <string>

#include "runtime/node/lag.h"
#include "test_support.h"
#include "tests/support/dds_scope.h"

namespace rths {
namespace {

class DdsForcePredictor : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

// 74 ms in all between command and answer (a 60 ms round trip and the actuator's 14 ms), with a
// model 30 % soft at the start: the online fit moves it, so the record checks the fit too.
constexpr const char* kPredicted =
    "cases { name: \"predicted\" delay { shift { delay: 0.060 } } delay { shift { delay: 0.014 } "
    "} force_predictor { stiffness_factor: 0.7 forgetting_time: 0.5 } }";

TEST_F(DdsForcePredictor, LockstepEqualsInProcessBitForBitAndRecordsThePredictionError) {
  const std::string text = test::paper_frame_study(2, kPredicted);
  const core::SimulationResult in_process = test::reference_result(text, "predicted");
  // The predictor acts: its error is recorded, and it departs from the run without it.
  const study::PreparedStudy prepared = test::prepare(text);
  core::HybridSetup bare =
      study::setup_for_case(prepared, study::find_case(prepared.config, "predicted"));
  ASSERT_EQ(bare.predictors.size(), 1u);
  bare.predictors.clear();
  const core::SimulationResult without = core::simulate(bare, prepared.motion);
  EXPECT_NE(without.displacement(1500, 0), in_process.displacement(1500, 0));
  EXPECT_GT(in_process.prediction_error.cwiseAbs().maxCoeff(), 0.0);

  const auto run =
      test::launch("force_predictor_lockstep", text, "predicted", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_FALSE(run.record.truncated);
  test::expect_record_equals(run.record, in_process);
  const auto steps = run.record.steps();
  std::size_t checked = 0;
  for (std::size_t k = 1; k < steps.size(); ++k) {
    for (const runtime::LinkSample& link : steps[k]->links()) {
      if (link.prediction_error_size() == 0) continue;
      ASSERT_EQ(link.prediction_error_size(), 1) << "node " << link.node_id();
      ASSERT_EQ(link.prediction_error(0),
                in_process.prediction_error(static_cast<Eigen::Index>(k), 0))
          << "step " << k;
      ++checked;
    }
  }
  EXPECT_EQ(checked, steps.size() - 1);  // one actuator link, every step after the first
}

// A column yielding sharply at the lab (bilinear, 0.5 mm) where the predictor's model is a smooth
// Bouc-Wen (force_predictor.model) with a lag term started at 2 ms: the coordinator builds and fits
// the same hysteretic model as core::simulate, so the lockstep run still equals it bit for bit.
TEST_F(DdsForcePredictor, AModelWithHysteresisAndLagIsTheSameInLockstep) {
  std::string text = test::paper_frame_study(
      2,
      "cases { name: \"hysteretic\" delay { shift { delay: 0.060 } } delay { shift { delay: "
      "0.014 } } force_predictor { stiffness_factor: 0.7 force_lag: 0.002 model { bouc_wen { "
      "yield_displacement: 0.0005 alpha: 0.02 } } } }");
  const std::string linear = "model { linear {} }";
  text.replace(text.find(linear), linear.size(),
               "model { bilinear { yield_displacement: 0.0005 post_yield_ratio: 0.02 } }");
  const core::SimulationResult in_process = test::reference_result(text, "hysteretic");
  ASSERT_EQ(in_process.predictor_models.size(), 1u);
  EXPECT_NE(in_process.predictor_models[0].find(", h "), std::string::npos)
      << in_process.predictor_models[0];
  const auto run = test::launch("force_predictor_hysteretic", text, "hysteretic",
                                test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_FALSE(run.record.truncated);
  test::expect_record_equals(run.record, in_process);
}

// A fixed model 50 % soft with a 20 % bound: the coordinator's fail-safe HOLDs the run at the
// step core::simulate stops at, naming the emulator's link.
TEST_F(DdsForcePredictor, BoundPastHoldsNamingTheLink) {
  const std::string text = test::paper_frame_study(
      4,
      "cases { name: \"held\" delay { shift { delay: 0.074 } } force_predictor { "
      "stiffness_factor: 0.5 fixed_model: true error_window: 0.2 max_relative_error: 0.2 } }");
  const core::SimulationResult in_process = test::reference_result(text, "held");
  ASSERT_FALSE(in_process.held.empty());
  const auto run =
      test::launch("force_predictor_hold", text, "held", test::scope_dds_to_this_test());
  EXPECT_NE(run.launch.coordinator_exit, 0);
  const std::string log = test::read_file(run.launch.coordinator_log);
  EXPECT_NE(log.find("force predictor of actuator 1 (link to"), std::string::npos) << log;
  EXPECT_NE(log.find("past its bound of 20 %"), std::string::npos) << log;
  EXPECT_LT(run.record.steps().size(), in_process.steps() + 2);
}

}  // namespace
}  // namespace rths
