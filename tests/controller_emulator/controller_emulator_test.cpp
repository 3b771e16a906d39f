// The controller emulator answers command frames with the in-process actuator's outputs bit for
// bit, holds on a HOLD status frame, refuses malformed frames and goes silent when told to. No
// sockets: step() takes and returns frames.
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

std::string study_text() {
  return test::paper_frame_study(0.5, "deployment { nodes { id: 2 kind: CONTROLLER controller { " +
                                          test::controller_link_text(47140, 47141) +
                                          " } } limits { max_displacement: 0.5 } }");
}

struct Emulator {
  config::Study study = core::parse_study(study_text(), "test");
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
  const core::PreparedStudy prepared = test::prepare(study_text());
  core::HybridSetup setup =
      core::setup_for_case(prepared, runtime::find_case(prepared.config, "lag_shift_14ms"));
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

TEST(ControllerEmulator, HoldsOnAHoldFrameAndAnswersHoldingFromThen) {
  Emulator e;
  for (int k = 1; k <= 50; ++k) ASSERT_TRUE(e.send(k, 0, k * 0.001, 0.0002 * k, 0.2));
  EXPECT_FALSE(e.send(51, controller_node::kStatusHold, 0.051, 0.0102, 0.2));
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
  const config::Study study = core::parse_study(test::paper_frame_study(0.5, ""), "test");
  EXPECT_THROW(ControllerEmulator(study, std::filesystem::temp_directory_path(), "", 2),
               std::invalid_argument);
}

}  // namespace
}  // namespace rths::controller_emulator
