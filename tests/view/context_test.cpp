#include "view/context.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>

#include "analysis/study_run/study_run.h"
#include "runtime/node/plan.h"
#include "tests/runtime/test_support.h"
#include "tests/support/in_process_run.h"
#include "tests/view/recorded_run.h"

namespace rths::view {
namespace {

std::filesystem::path record_path(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("rths_view_context_" + name + "_" + std::to_string(::getpid()) + ".rthsrec");
}

// The coordinator with its node services in one process (the reference a lockstep run over DDS
// equals bit for bit), its record fed to a view given the prediction as the coordinator gives it:
// measured and predicted are the same doubles at every sample.
TEST(Context, ALockstepRunEqualsItsPredictionOnThePageAtEverySample) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(2.0, ""));
  Feed feed;
  describe_run(feed, prepared, "lag_shift_14ms");
  coordinator::CoordinatorOptions options;
  options.run_id = "view-context";
  options.case_name = "lag_shift_14ms";
  options.record = record_path("lockstep");
  options.record_observer = &feed;
  const auto outcome = coordinator::run_in_process(prepared, options);
  std::filesystem::remove(options.record);
  ASSERT_TRUE(outcome.ok) << outcome.status;
  FeedCursor cursor;
  const auto j = feed.since(cursor);
  EXPECT_NE(j["context"]["prediction"]["text"].get<std::string>().find("lag_shift_14ms"),
            std::string::npos);
  EXPECT_EQ(j["context"]["prediction"]["steps"], outcome.result.steps());
  EXPECT_EQ(j["context"]["node_kinds"],
            nlohmann::json({{"1", "SUBSTRUCTURE"}, {"2", "ACTUATOR_EMULATOR"}}));
  const auto& samples = j["samples"];
  const std::size_t steps = prepared.motion.acceleration.size();
  ASSERT_EQ(samples["step"].size(), (steps + 9) / 10);  // every 10th step from 0
  for (std::size_t i = 0; i < samples["step"].size(); ++i) {
    const auto k = samples["step"][i].get<Eigen::Index>();
    EXPECT_EQ(samples["predicted_u_mm"][0][i].get<double>(),
              outcome.result.displacement(k, 0) * 1e3);
    EXPECT_EQ(samples["difference_mm"][0][i].get<double>(), 0.0) << "step " << k;
  }
  EXPECT_EQ(j["status"]["prediction"]["compared_samples"], (steps + 9) / 10);
  EXPECT_EQ(j["status"]["prediction"]["max_abs_difference_mm"][0].get<double>(), 0.0);
  EXPECT_GT(outcome.result.displacement.cwiseAbs().maxCoeff(), 1e-4);  // a response to compare
}

// What the control room shows per link: the actuators of each node, the answer window, the
// critical round trip (uncompensated here: the case has no predictor) less the case's own lag;
// and per link in the samples, the answer age (0 in lockstep: each step applies its own
// answer), the answers accepted (one per step) and no predictor error.
TEST(Context, TheLinksFactsAndColumnsAreTheRunsOwn) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(0.5, ""));
  Feed feed;
  describe_run(feed, prepared, "lag_shift_14ms");
  coordinator::CoordinatorOptions options;
  options.run_id = "view-context-links";
  options.case_name = "lag_shift_14ms";
  options.record = record_path("links");
  options.record_observer = &feed;
  const auto outcome = coordinator::run_in_process(prepared, options);
  std::filesystem::remove(options.record);
  ASSERT_TRUE(outcome.ok) << outcome.status;
  FeedCursor cursor;
  const auto j = feed.since(cursor);
  EXPECT_EQ(j["context"]["node_actuators"],
            nlohmann::json({{"1", nlohmann::json::array()}, {"2", nlohmann::json::array({0})}}));
  const config::Deployment deployment =
      runtime::with_default_nodes(prepared.config.deployment(), prepared.base);
  EXPECT_EQ(j["context"]["answer_window_steps"],
            runtime::max_missed_answers(deployment, prepared.base.dt));
  const auto check = analysis::check_case_critical_delay(
      prepared, study::find_case(prepared.config, "lag_shift_14ms"));
  ASSERT_TRUE(check && check->critical());
  const auto& critical = j["context"]["critical_round_trip"];
  EXPECT_EQ(critical["label"], "uncompensated");
  EXPECT_NEAR(critical["ms"].get<double>(), (*check->critical() - 0.014) * 1e3, 1e-9);
  const auto& samples = j["samples"];
  const std::size_t last = samples["step"].size() - 1;
  for (std::size_t l = 0; l < 2; ++l) {
    EXPECT_EQ(samples["answer_age_steps"][l][last].get<double>(), 0.0) << "link " << l;
    EXPECT_EQ(samples["answers"][l][last].get<double>(), samples["step"][last].get<double>());
    // NaN, which the page receives as null: the case has no predictor.
    EXPECT_TRUE(std::isnan(samples["prediction_error_N"][l][last].get<double>()));
  }
}

// A case with a force predictor: the critical round trip is the compensated loop's, as
// analysis::predicted_loop_verdict finds it (here the exact model as it starts: stable for every
// round trip, so no figure but "unbounded"), never the uncompensated one.
TEST(Context, ThePredictedLoopsCriticalRoundTripIsTheCompensatedOne) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(
      0.5, "cases { name: \"predicted\" delay { shift { delay: 0.014 } } force_predictor { } }\n"));
  const auto verdict = analysis::predicted_loop_verdict(
      prepared, study::find_case(prepared.config, "predicted"), 0.0);
  ASSERT_TRUE(verdict && verdict->analysed && verdict->stable) << (verdict ? verdict->text : "");
  const auto critical = link_context(prepared, "predicted")["critical_round_trip"];
  EXPECT_EQ(critical["label"], "compensated (force predictor as it starts)");
  EXPECT_EQ(critical["text"], verdict->text);
  if (verdict->extra_delay_tolerated)
    EXPECT_NEAR(critical["ms"].get<double>(), *verdict->extra_delay_tolerated * 1e3, 1e-9);
  else
    EXPECT_TRUE(critical["unbounded"].get<bool>());
  EXPECT_EQ(link_context(prepared, "lag_shift_14ms")["critical_round_trip"]["label"],
            "uncompensated");
}

TEST(Context, APredictionIsTheInProcessRunOfTheCaseWithItsDelays) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(1.0, ""));
  const core::SimulationResult lagged = predict_case(prepared, "lag_shift_14ms");
  const core::SimulationResult reference = predict_case(prepared, "reference");
  ASSERT_EQ(lagged.steps(), prepared.motion.acceleration.size());
  const auto& study_case = study::find_case(prepared.config, "lag_shift_14ms");
  EXPECT_TRUE(
      lagged.displacement ==
      core::simulate(study::setup_for_case(prepared, study_case), prepared.motion).displacement);
  EXPECT_FALSE(lagged.displacement == reference.displacement);
  EXPECT_THROW(predict_case(prepared, "no_such_case"), std::invalid_argument);
}

// The prediction keeps what the study's recorders keep (the record's columns), each kept DOF's
// history the one a prediction of every DOF has.
TEST(Context, APredictionKeepsTheDofsTheRecordersKeep) {
  study::PreparedStudy prepared = test::prepare(
      test::two_storey_study(1.0, "cases { name: \"lag\" delay { shift { delay: 0.01 } } }", ""));
  ASSERT_EQ(prepared.base.model.dofs(), 2);
  const core::SimulationResult every = predict_case(prepared, "lag");
  prepared.recorders.kept_dofs = {1};
  const core::SimulationResult kept = predict_case(prepared, "lag");
  EXPECT_EQ(kept.dofs, std::vector<int>{1});
  ASSERT_EQ(kept.displacement.cols(), 1);
  EXPECT_TRUE(kept.displacement.col(0) == every.displacement.col(1));
}

// The paper frame's lag_shift_14ms run, recorded, read back and removed from disk.
runtime::RecordContents recorded_paper_frame(const study::PreparedStudy& prepared,
                                             const std::string& name) {
  return test::recorded_paper_frame(prepared, "view-record-" + name, record_path(name));
}

// The page's data after describing the record, its header's motion file renamed away.
nlohmann::json described_away_from_its_motion(runtime::RecordContents& contents) {
  contents.entries.front().mutable_header()->mutable_study()->mutable_motion()->set_path(
      "moved_away.AT2");
  Feed feed;
  describe_record(feed, contents, std::filesystem::temp_directory_path());
  for (const auto& entry : contents.entries) feed.add(entry);
  FeedCursor cursor;
  return feed.since(cursor);
}

// A record carries its inputs: its study's motion file gone, the prediction runs on the motion
// its inputs entry carries, says so, and is the in-process run's, bit for bit.
TEST(Context, ARecordAwayFromItsMotionFilePredictsOverTheMotionItCarries) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(1.0, ""));
  runtime::RecordContents contents = recorded_paper_frame(prepared, "embedded");
  ASSERT_TRUE(contents.entries.at(1).has_inputs());  // right after the header
  auto& motion = *contents.entries.at(1).mutable_inputs()->mutable_study()->mutable_motion();
  ASSERT_TRUE(motion.has_embedded());
  motion.set_path("moved_away.AT2");
  const auto j = described_away_from_its_motion(contents);
  const std::string text = j["context"]["prediction"]["text"];
  EXPECT_NE(text.find("inputs embedded in the record"), std::string::npos) << text;
  EXPECT_EQ(j["status"]["prediction"]["max_abs_difference_mm"][0].get<double>(), 0.0);
}

// An older record, without embedded inputs, its study's motion file gone: the record's own steps
// carry the motion, and the prediction over them is the in-process run's, bit for bit.
TEST(Context, AnOlderRecordAwayFromItsMotionFilePredictsOverTheMotionItsStepsCarry) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(1.0, ""));
  runtime::RecordContents contents = recorded_paper_frame(prepared, "away");
  ASSERT_TRUE(contents.entries.front().has_header());
  EXPECT_EQ(recorded_motion(contents).acceleration, prepared.motion.acceleration);
  // As a record written before records carried their inputs (or its inputs entry damaged).
  contents.entries.erase(contents.entries.begin() + 1);
  const auto j = described_away_from_its_motion(contents);
  const std::string text = j["context"]["prediction"]["text"];
  const std::size_t steps = prepared.motion.acceleration.size();
  EXPECT_NE(text.find("over the motion of the record's " + std::to_string(steps) + " steps"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("moved_away.AT2"), std::string::npos) << text;
  EXPECT_EQ(j["status"]["prediction"]["compared_samples"], (steps + 9) / 10);
  EXPECT_EQ(j["status"]["prediction"]["max_abs_difference_mm"][0].get<double>(), 0.0);
}

TEST(Context, WithoutAnyMotionThePageSaysWhyThereIsNoPrediction) {
  runtime::RecordContents contents;
  contents.warning = "cut short at byte 9";
  auto& header = *contents.entries.emplace_back().mutable_header();
  header.set_dt(0.001);
  header.set_dofs(1);
  *header.mutable_study() = study::parse_study(
      "name: \"lost\"\nstructure { sdof { period: 0.5 } }\n"
      "motion { path: \"missing_motion.AT2\" }\nintegrator { dt: 0.001 }\n"
      "substructuring { experimental_fraction: 0.5 model { linear {} } }\n",
      "test");
  Feed feed;
  describe_record(feed, contents, std::filesystem::temp_directory_path());
  feed.add(contents.entries.front());
  FeedCursor cursor;
  const auto j = feed.since(cursor);
  const std::string text = j["context"]["prediction"]["text"];
  EXPECT_EQ(text.rfind("no in-process prediction: ", 0), 0u) << text;
  EXPECT_NE(text.find("missing_motion.AT2"), std::string::npos) << text;
  EXPECT_EQ(j["context"]["note"], "cut short at byte 9");
  EXPECT_FALSE(j["status"].contains("prediction"));
}

}  // namespace
}  // namespace rths::view
