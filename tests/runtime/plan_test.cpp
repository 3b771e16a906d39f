#include "runtime/node/plan.h"

#include <google/protobuf/text_format.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>

#include "test_support.h"

namespace rths::runtime {
namespace {

core::HybridSetup two_storey_fraction() {
  return test::prepare(test::two_storey_study(
                           0.1, "cases { name: \"r\" }", "",
                           "substructuring { experimental_fraction: 0.5 model { linear {} } }"))
      .base;
}

config::Deployment deployment(const std::string& text) {
  config::Deployment d;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &d)) << text;
  return d;
}

std::string error_of(const core::HybridSetup& setup, const std::string& text) {
  try {
    make_plan(setup, deployment(text));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Plan, DefaultNodesHostEverything) {
  const auto setup = two_storey_fraction();
  const auto plan = make_plan(setup, with_default_nodes(config::Deployment{}, setup));
  ASSERT_EQ(plan.nodes.size(), 2u);
  EXPECT_EQ(plan.nodes[0].storeys, (std::vector<int>{0, 1}));
  EXPECT_EQ(plan.nodes[1].actuators, (std::vector<int>{0, 1}));
  EXPECT_FALSE(plan.numerical_local);
}

TEST(Plan, NoSubstructureNodeMeansTheCoordinatorComputesTheNumericalPart) {
  const auto plan =
      make_plan(two_storey_fraction(), deployment("nodes { id: 4 kind: ACTUATOR_EMULATOR }"));
  EXPECT_TRUE(plan.numerical_local);
}

TEST(Plan, ErrorsNameNodeAndStorey) {
  const auto setup = two_storey_fraction();
  EXPECT_NE(error_of(setup,
                     "nodes { id: 1 kind: SUBSTRUCTURE storeys: [1] } "
                     "nodes { id: 2 kind: ACTUATOR_EMULATOR }")
                .find("numerical storey 2 is hosted by no substructure node"),
            std::string::npos);
  EXPECT_NE(error_of(setup,
                     "nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 3 kind: SUBSTRUCTURE } "
                     "nodes { id: 2 kind: ACTUATOR_EMULATOR }")
                .find("storey 1 is hosted by nodes 1 and 3"),
            std::string::npos);
  EXPECT_NE(error_of(setup, "nodes { id: 0 kind: SUBSTRUCTURE }").find("id must be >= 1"),
            std::string::npos);
  EXPECT_NE(error_of(setup, "nodes { id: 1 kind: SUBSTRUCTURE storeys: [3] }")
                .find("storey 3 does not exist"),
            std::string::npos);
  EXPECT_NE(
      error_of(setup, "nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 1 kind: ACTUATOR_EMULATOR }")
          .find("id used by two nodes"),
      std::string::npos);
  EXPECT_NE(error_of(setup, "nodes { id: 1 kind: SUBSTRUCTURE }")
                .find("experimental storey 1 is hosted by no actuator emulator"),
            std::string::npos);
}

TEST(Plan, NodeSideSetupMatchesPrepareStudy) {
  const std::string text =
      test::two_storey_study(0.1, "cases { name: \"d\" delay { shift { delay: 0.01 } } }", "");
  const auto prepared = test::prepare(text);
  const auto& c = study::find_case(prepared.config, "d");
  const auto from_core = study::setup_for_case(prepared, c);
  const auto node_side =
      setup_without_motion(prepared.config, prepared.base_dir, prepared.base.dt, c);
  EXPECT_EQ(from_core.partition.actuator_storeys, node_side.partition.actuator_storeys);
  ASSERT_EQ(from_core.delays.size(), node_side.delays.size());
  for (std::size_t s = 0; s < from_core.partition.numerical.size(); ++s) {
    ASSERT_EQ(!from_core.partition.numerical[s], !node_side.partition.numerical[s]);
    if (from_core.partition.numerical[s])
      EXPECT_EQ(from_core.partition.numerical[s]->describe(),
                node_side.partition.numerical[s]->describe());
  }
  EXPECT_EQ(from_core.delays[0].describe(), node_side.delays[0].describe());
}

// The shipped 2,000-DOF real-time study (issue 63): its matrices read and checked, its deployment
// accepted, every DOF on its substructure node, at 1024 Hz with the loop and DDS threads raised.
TEST(Plan, TheShippedTwoThousandDofRealTimeStudyPutsEveryDofOnItsNode) {
  const std::filesystem::path configs = RTHS_SOURCE_DIR "/configs";
  const study::PreparedStudy prepared =
      study::prepare_study(study::load_study(configs / "chain2000_realtime.textproto"), configs);
  EXPECT_EQ(prepared.base.model.dofs(), 2000);
  EXPECT_DOUBLE_EQ(prepared.base.dt, 1.0 / 1024);
  EXPECT_EQ(prepared.motion.acceleration.size(), 20480u);
  check_deployment(prepared);
  const config::Deployment& d = prepared.config.deployment();
  EXPECT_EQ(d.clock(), config::Deployment::REAL_TIME);
  EXPECT_EQ(realtime_priority(d), 80);
  const DeploymentPlan plan = make_plan(prepared.base, d);
  EXPECT_FALSE(plan.numerical_local);
  const NodePlan* node = plan.find(1);
  ASSERT_NE(node, nullptr);
  EXPECT_EQ(node->spec.kind(), config::NodeSpec::SUBSTRUCTURE);
  EXPECT_EQ(node->storeys.size(), 2000u);
  ASSERT_NE(plan.find(2), nullptr);
  EXPECT_EQ(plan.find(2)->actuators, (std::vector<int>{0}));
}

TEST(Plan, LockstepJudgesANodeDeadOnlyAfterSecondsOfSilenceRealTimeAfterItsOwnTimeout) {
  config::Deployment d;
  d.set_liveliness_timeout(1.0);
  EXPECT_DOUBLE_EQ(judged_liveliness_timeout(d), kLockstepLivelinessFloor);
  d.set_liveliness_timeout(8.0);
  EXPECT_DOUBLE_EQ(judged_liveliness_timeout(d), 8.0);
  d.set_clock(config::Deployment::REAL_TIME);
  d.set_liveliness_timeout(0.3);
  EXPECT_DOUBLE_EQ(judged_liveliness_timeout(d), 0.3);
}

TEST(FailSafeWindows, StepsFromMillisecondsOrTheStepFields) {
  const double dt = 1.0 / 1024;
  EXPECT_EQ(max_missed_answers(deployment(""), dt), 3);
  EXPECT_EQ(command_watchdog_periods(deployment(""), dt), 3);
  EXPECT_EQ(max_missed_answers(deployment("max_missed_answers: 7"), dt), 7);
  EXPECT_EQ(command_watchdog_periods(deployment("command_watchdog_periods: 5"), dt), 5);
  EXPECT_EQ(max_missed_answers(deployment("answer_window_ms: 10"), dt), 11);  // ceil(10.24)
  EXPECT_EQ(command_watchdog_periods(deployment("command_watchdog_ms: 8"), dt), 9);
  // Unset, the watchdog follows a widened answer window (20 ms: 21 periods), never under 3.
  EXPECT_EQ(command_watchdog_periods(deployment("answer_window_ms: 20"), dt), 21);
  EXPECT_EQ(command_watchdog_periods(deployment("max_missed_answers: 2"), dt), 3);
  EXPECT_EQ(
      command_watchdog_periods(deployment("answer_window_ms: 20 command_watchdog_periods: 4"), dt),
      4);
  EXPECT_EQ(max_missed_answers(deployment("answer_window_ms: 3"), 0.001), 3);  // exactly 3 steps
  EXPECT_EQ(max_missed_answers(deployment("answer_window_ms: 0.1"), 0.001), 1);
}

TEST(FailSafeWindows, AWindowFoundInStepsIsStatedInMillisecondsThatGiveTheSameSteps) {
  for (const double dt : {1.0 / 1024, 1.0 / 4096, 0.001, 0.01, 1.0 / 60, 1.0 / 3000})
    for (int steps = 1; steps <= 3000; ++steps) {
      const double ms = window_ms_of_steps(steps, dt);
      ASSERT_LE(ms, 1e3 * steps * dt);
      ASSERT_GE(ms, 1e3 * steps * dt - 1e-3 - 1e-9);  // at most a microsecond below
      char text[64];  // as the platform check prints it in the fix it offers
      std::snprintf(text, sizeof text, "answer_window_ms: %.3f", ms);
      ASSERT_EQ(max_missed_answers(deployment(text), dt), steps) << text << " at dt " << dt;
    }
  EXPECT_DOUBLE_EQ(window_ms_of_steps(20, 1.0 / 1024), 19.531);
}

TEST(FailSafeWindows, BothWaysOrOutOfRangeIsBadInputNamingTheFields) {
  const core::HybridSetup setup = two_storey_fraction();
  EXPECT_EQ(error_of(setup, "answer_window_ms: 10 max_missed_answers: 4"),
            "deployment.answer_window_ms and deployment.max_missed_answers both given "
            "(10.000000 ms and 4 steps): give the window one way");
  EXPECT_NE(error_of(setup, "command_watchdog_ms: -1")
                .find("deployment.command_watchdog_ms = -1.000000 ms: must be in [0, 60000] ms"),
            std::string::npos);
  EXPECT_NE(error_of(setup, "answer_window_ms: 70000").find("[0, 60000]"), std::string::npos);
  EXPECT_NO_THROW(
      check_failsafe_windows(deployment("answer_window_ms: 10 command_watchdog_periods: 4")));
}

// What a person reads before the run: every window and plausibility check with its bound, the
// checks on by default (jump 0.2 mm, tracking at 50 ms) and the watchdog following the answer
// window when unset (20 ms at 1/1024 s: 21 periods).
TEST(ControllerLink, TheChecksLineNamesEveryWindowAndBoundWithTheDefaultsOn) {
  config::Deployment real_time;
  real_time.set_clock(config::Deployment::REAL_TIME);
  real_time.set_answer_window_ms(20);
  real_time.mutable_limits()->set_max_velocity(2.0);
  config::ControllerLink link;
  ASSERT_TRUE(google::protobuf::TextFormat::ParseFromString("max_force: 20000", &link));
  const std::string text = controller_checks_text(link, real_time, 1.0 / 1024);
  for (const char* part :
       {"answer window 21 steps (20.508 ms)", "command watchdog 21 periods (20.508 ms)",
        "hold time 500 ms", "measured rate <= 4.000 m/s",
        "measured jump <= 2 x peak target velocity x span + 0.200 mm",
        "tracking <= 2 x peak target velocity x 50.0 ms + 1.200 mm for 3 answers", "force rate off",
        "max force <= 20000 N"})
    EXPECT_NE(text.find(part), std::string::npos) << part << " in: " << text;
  link.set_jump_floor(-1);
  link.set_expected_lag_ms(14);
  const std::string off = controller_checks_text(link, real_time, 1.0 / 1024);
  EXPECT_NE(off.find("measured jump off"), std::string::npos) << off;
  EXPECT_NE(off.find("x 14.0 ms + 1.000 mm"), std::string::npos) << off;
  EXPECT_NE(controller_checks_text(link, config::Deployment{}, 0.001)
                .find("command watchdog off (lockstep)"),
            std::string::npos);
}

// The loop's priority as set, in real time and not spinning; never unset: the pre-run check
// recommends it instead.
TEST(RealtimePriority, AsSetInRealTimeAndRecommendedWhenUnset) {
  config::Deployment d;
  d.set_clock(config::Deployment::REAL_TIME);
  EXPECT_EQ(realtime_priority(d), 0);
  if (geteuid() == 0) {
    EXPECT_NE(realtime_priority_text(d).find("off (unset: realtime_priority: 50 keeps"),
              std::string::npos)
        << realtime_priority_text(d);
  }
  d.set_realtime_priority(20);
  EXPECT_EQ(realtime_priority(d), 20);
  EXPECT_EQ(realtime_priority_text(d), "SCHED_FIFO 20 (set)");
  d.set_realtime_priority(-1);
  EXPECT_EQ(realtime_priority(d), 0);
  EXPECT_EQ(realtime_priority_text(d), "off (realtime_priority: -1)");
  d.set_realtime_priority(20);
  d.set_wait_policy(config::WAIT_SPIN);
  EXPECT_EQ(realtime_priority(d), 0);
  d.set_wait_policy(config::WAIT_SLEEP);
  d.set_clock(config::Deployment::LOCKSTEP);
  EXPECT_EQ(realtime_priority(d), 0);
  EXPECT_EQ(realtime_priority_text(d), "off (lockstep)");
}

}  // namespace
}  // namespace rths::runtime
