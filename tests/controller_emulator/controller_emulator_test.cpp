// The controller emulator answers command frames with the in-process actuator's outputs bit for
// bit, holds on a HOLD status frame, refuses malformed frames and goes silent when told to; paced
// (real time, a servo faster than the integrator), a frame only loads the servo and is answered
// with the newest plant period's state. No sockets: step() takes and returns frames, the test
// calls tick() for the plant's clock.
#include "controller_emulator/controller_emulator.h"

#include <gtest/gtest.h>

#include <cmath>

#include "../controller_node/link_text.h"
#include "../runtime/test_support.h"
#include "controller_node/controller_exchange.h"
#include "controller_node/frame.h"

namespace rths::controller_emulator {
namespace {

using controller_node::FrameValues;

std::string study_text(const std::string& deployment_extra = "") {
  return test::paper_frame_study(0.5, "deployment { nodes { id: 2 kind: CONTROLLER controller { " +
                                          test::controller_link_text(47140, 47141) +
                                          " } } limits { max_displacement: 0.5 } " +
                                          deployment_extra + " }");
}

// Real time at dt = 1 ms with a 4000 Hz servo: the emulator's plant runs 4 periods per step.
std::string paced_study_text() { return study_text("clock: REAL_TIME") + " servo { rate: 4000 }"; }

struct Emulator {
  explicit Emulator(const std::string& text = study_text())
      : study(study::parse_study(text, "test")) {}
  config::Study study;
  ControllerEmulator emulator{study, std::filesystem::temp_directory_path(), "lag_shift_14ms", 2};

  std::optional<FrameValues> send(std::int64_t counter, std::int64_t status, double time,
                                  double drift, double velocity) {
    FrameValues v;
    v.counter = counter;
    v.status = status;
    v.time = time;
    v.target_displacement = {drift};
    v.target_velocity = {velocity};
    std::vector<std::uint8_t> bytes;
    EXPECT_TRUE(controller_node::encode(emulator.link().command(), v, bytes));
    const auto answer = emulator.step(bytes.data(), bytes.size());
    if (!answer) return std::nullopt;
    FrameValues out;
    EXPECT_EQ(
        controller_node::decode(emulator.link().feedback(), answer->data(), answer->size(), 1, out),
        controller_node::FrameVerdict::kOk);
    return out;
  }
};

TEST(ControllerEmulator, AnswersEachCommandFrameAsTheInProcessActuatorBitForBit) {
  Emulator e;
  const study::PreparedStudy prepared = test::prepare(study_text());
  core::HybridSetup setup =
      study::setup_for_case(prepared, study::find_case(prepared.config, "lag_shift_14ms"));
  core::Actuator actuator =
      core::make_actuator(setup.partition, 0, setup.delays.at(0), setup.dt, setup.servo_substeps);
  for (int k = 1; k <= 200; ++k) {
    const double t = k * setup.dt;
    const double drift = 0.01 * std::sin(2 * M_PI * 2 * t);
    const double velocity = 0.01 * 2 * M_PI * 2 * std::cos(2 * M_PI * 2 * t);
    const core::ActuatorOutput expected = actuator.step({t, drift, velocity});
    const auto answer = e.send(k, controller_node::kStatusRun, t, drift, velocity);
    ASSERT_TRUE(answer) << "step " << k;
    EXPECT_EQ(answer->counter, k);
    EXPECT_EQ(answer->status, controller_node::kStatusRun);
    ASSERT_EQ(answer->measured_displacement[0], expected.realised) << "step " << k;
    ASSERT_EQ(answer->measured_force[0], expected.force) << "step " << k;
  }
  EXPECT_EQ(e.emulator.counts().answered, 200u);
}

TEST(ControllerEmulator, AnswersPerFrameInLockstepAndPacesItsPlantInRealTime) {
  EXPECT_FALSE(Emulator().emulator.paced());
  Emulator e(paced_study_text());
  ASSERT_TRUE(e.emulator.paced());
  EXPECT_DOUBLE_EQ(e.emulator.plant_period(), 0.001 / 4);
}

TEST(ControllerEmulator, PacedAnswersEachFrameWithTheNewestPlantPeriodOfTheInProcessServo) {
  Emulator e(paced_study_text());
  const study::PreparedStudy prepared = test::prepare(paced_study_text());
  core::HybridSetup setup =
      study::setup_for_case(prepared, study::find_case(prepared.config, "lag_shift_14ms"));
  ASSERT_EQ(setup.servo_substeps, 4);
  core::Actuator actuator =
      core::make_actuator(setup.partition, 0, setup.delays.at(0), setup.dt, setup.servo_substeps);
  e.emulator.tick(false);  // before the first command the plant is at rest
  core::ActuatorOutput newest{};
  for (int k = 1; k <= 100; ++k) {
    const double t = k * setup.dt;
    const double drift = 0.01 * std::sin(2 * M_PI * 2 * t);
    const double velocity = 0.01 * 2 * M_PI * 2 * std::cos(2 * M_PI * 2 * t);
    const auto answer = e.send(k, controller_node::kStatusRun, t, drift, velocity);
    ASSERT_TRUE(answer) << "frame " << k;
    EXPECT_EQ(answer->counter, k);
    ASSERT_EQ(answer->measured_displacement[0], newest.realised) << "frame " << k;
    ASSERT_EQ(answer->measured_force[0], newest.force) << "frame " << k;
    actuator.command({t, drift, velocity});
    // A busy plant may fall behind by a period or run one more; the answer is whatever it reached.
    const int periods = k % 10 == 0 ? 3 : 4;
    for (int j = 0; j < periods; ++j) {
      e.emulator.tick(j == 0 && k % 10 == 0);
      newest = actuator.tick();
    }
  }
  EXPECT_EQ(e.emulator.counts().answered, 100u);
  EXPECT_EQ(e.emulator.counts().ticks, 1u + 90 * 4 + 10 * 3);
  EXPECT_EQ(e.emulator.counts().overruns, 10u);
}

TEST(ControllerEmulator, PacedHoldsOnAHoldFrameAndItsPlantStaysAtTheHoldPosition) {
  Emulator e(paced_study_text());
  for (int k = 1; k <= 50; ++k) {
    ASSERT_TRUE(e.send(k, 0, k * 0.001, 0.0002 * k, 0.2));
    for (int j = 0; j < 4; ++j) e.emulator.tick(false);
  }
  // A HOLD frame is answered at once: status HOLD (held) at the position the plant holds.
  const auto held = e.send(51, controller_node::kStatusHold, 0.051, 0.0102, 0.2);
  ASSERT_TRUE(held);
  EXPECT_EQ(held->status, controller_node::kStatusHold);
  EXPECT_EQ(held->counter, 51);
  for (int j = 0; j < 40; ++j) e.emulator.tick(false);
  const auto answer = e.send(52, 0, 0.052, 0.0104, 0.2);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->status, controller_node::kStatusHold);
  EXPECT_GT(answer->measured_displacement[0], 0.0);
  EXPECT_LT(answer->measured_displacement[0], 0.0102);
}

TEST(ControllerEmulator, HoldsOnAHoldFrameAnswersItHeldAndAnswersHoldingFromThen) {
  Emulator e;
  for (int k = 1; k <= 50; ++k) ASSERT_TRUE(e.send(k, 0, k * 0.001, 0.0002 * k, 0.2));
  const auto held = e.send(51, controller_node::kStatusHold, 0.051, 0.0102, 0.2);
  ASSERT_TRUE(held);
  EXPECT_EQ(held->status, controller_node::kStatusHold);
  EXPECT_EQ(held->counter, 51);
  EXPECT_EQ(e.emulator.counts().holds, 1u);
  const auto answer = e.send(52, 0, 0.052, 0.0104, 0.2);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->status, controller_node::kStatusHold);
  EXPECT_FALSE(e.send(53, controller_node::kStatusStop, 0.053, 0.0, 0.0));
  EXPECT_TRUE(e.emulator.stopped());
}

TEST(ControllerEmulator, RefusesMalformedFramesAndGoesSilentWhenTold) {
  Emulator e;
  const std::vector<std::uint8_t> short_frame(31, 0);
  EXPECT_FALSE(e.emulator.step(short_frame.data(), short_frame.size()));
  std::vector<std::uint8_t> nan_frame(32, 0xFF);  // every f64 a NaN
  EXPECT_FALSE(e.emulator.step(nan_frame.data(), nan_frame.size()));
  EXPECT_EQ(e.emulator.counts().rejected, 2u);

  ControllerEmulator silent(e.study, std::filesystem::temp_directory_path(), "reference", 2, 2);
  std::vector<std::uint8_t> bytes;
  int answered = 0;
  for (int k = 1; k <= 4; ++k) {
    FrameValues v;
    v.counter = k;
    v.target_displacement = {0.0};
    v.target_velocity = {0.0};
    ASSERT_TRUE(controller_node::encode(silent.link().command(), v, bytes));
    answered += silent.step(bytes.data(), bytes.size()).has_value();
  }
  EXPECT_EQ(answered, 2);
  EXPECT_EQ(silent.counts().commands, 4u);
}

TEST(ControllerEmulator, RefusesANodeThatIsNotAController) {
  const config::Study study = study::parse_study(test::paper_frame_study(0.5, ""), "test");
  EXPECT_THROW(ControllerEmulator(study, std::filesystem::temp_directory_path(), "", 2),
               std::invalid_argument);
}

}  // namespace
}  // namespace rths::controller_emulator
