// The frame codec: layouts checked field by field, every type and byte order packed to known
// bytes, scales, and the two ways a frame is refused (size, a value not finite).
#include "controller_node/frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "link_text.h"

namespace rths::controller_node {
namespace {

config::FrameLayout layout(const std::string& text) {
  config::FrameLayout l;
  EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, &l)) << text;
  return l;
}

std::string refusal(const std::string& text, int actuators, Direction direction) {
  try {
    runtime::check_frame_layout(layout(text), actuators, direction, "controller.command");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Frame, TheTestLayoutsAreValidAndSized) {
  const config::ControllerLink link = test::controller_link(1, 2);
  EXPECT_NO_THROW(runtime::check_frame_layout(link.command(), 1, Direction::kCommand, "command"));
  EXPECT_NO_THROW(
      runtime::check_frame_layout(link.feedback(), 1, Direction::kFeedback, "feedback"));
  EXPECT_EQ(frame_size(link.command()), 32u);
  EXPECT_EQ(frame_size(link.feedback()), 24u);
}

TEST(Frame, BadLayoutsAreRefusedNamingTheField) {
  const std::string counter = "fields { name: \"c\" role: COUNTER type: U32 } ";
  const std::string target = "fields { name: \"x\" role: TARGET_DISPLACEMENT } ";
  EXPECT_NE(refusal(target, 1, Direction::kCommand).find("no COUNTER field"), std::string::npos);
  EXPECT_NE(refusal(counter, 1, Direction::kCommand).find("no TARGET_DISPLACEMENT field"),
            std::string::npos);
  EXPECT_NE(
      refusal("fields { name: \"c\" role: COUNTER type: F64 } " + target, 1, Direction::kCommand)
          .find("fields[0] (c): a COUNTER field is I32 or U32"),
      std::string::npos);
  EXPECT_NE(refusal(counter + target + "fields { name: \"f\" role: MEASURED_FORCE }", 1,
                    Direction::kCommand)
                .find("fields[2] (f): role MEASURED_FORCE belongs to the other direction"),
            std::string::npos);
  EXPECT_NE(refusal(counter + target + target, 1, Direction::kCommand)
                .find("a second TARGET_DISPLACEMENT field"),
            std::string::npos);
  EXPECT_NE(
      refusal(counter + "fields { role: TARGET_DISPLACEMENT actuator: 1 }", 1, Direction::kCommand)
          .find("actuator 1 is not among the node's 1"),
      std::string::npos);
  EXPECT_NE(
      refusal(counter + "fields { role: TARGET_DISPLACEMENT scale: -1 }", 1, Direction::kCommand)
          .find("scale must be finite"),
      std::string::npos);
  EXPECT_NE(refusal(counter + target + "fields { name: \"t\" }", 1, Direction::kCommand)
                .find("fields[2] (t): role not set"),
            std::string::npos);
  EXPECT_NE(refusal(counter + "fields { role: MEASURED_FORCE }", 1, Direction::kFeedback)
                .find("no MEASURED_DISPLACEMENT field for actuator 0"),
            std::string::npos);
}

TEST(Frame, EachTypeAndByteOrderPacksToKnownBytes) {
  const config::FrameLayout l = layout(
      "fields { role: COUNTER type: U32 byte_order: ORDER_BIG } "
      "fields { role: STATUS type: I32 } "
      "fields { role: TARGET_DISPLACEMENT type: F32 byte_order: ORDER_BIG scale: 0.001 } "
      "fields { role: TARGET_VELOCITY type: I32 byte_order: ORDER_BIG scale: 1e-6 } "
      "fields { role: PADDING type: U32 } "
      "fields { role: COMMAND_TIME type: F64 byte_order: ORDER_BIG }");
  FrameValues v;
  v.counter = 0x01020304;
  v.status = -2;
  v.target_displacement = {0.0125};  // 12.5 mm as f32: 0x41480000
  v.target_velocity = {-0.000003};   // -3 um/s as i32 counts of 1e-6
  v.time = 1.5;                      // 0x3FF8000000000000
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encode(l, v, bytes));
  const std::vector<std::uint8_t> expected = {
      0x01, 0x02, 0x03, 0x04, 0xFE, 0xFF, 0xFF, 0xFF, 0x41, 0x48, 0x00, 0x00, 0xFF, 0xFF,
      0xFF, 0xFD, 0x00, 0x00, 0x00, 0x00, 0x3F, 0xF8, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};
  EXPECT_EQ(bytes, expected);
  FrameValues back;
  ASSERT_EQ(decode(l, bytes.data(), bytes.size(), 1, back), FrameVerdict::kOk);
  EXPECT_EQ(back.counter, v.counter);
  EXPECT_EQ(back.status, -2);
  EXPECT_TRUE(back.has_status);
  EXPECT_DOUBLE_EQ(back.target_displacement[0], 0.0125);
  EXPECT_DOUBLE_EQ(back.target_velocity[0], -0.000003);
  EXPECT_EQ(back.time, 1.5);
}

TEST(Frame, F64AtScaleOneCarriesADoublesBitsUnchanged) {
  const config::ControllerLink link = test::controller_link(1, 2);
  FrameValues v;
  v.counter = 7;
  v.time = 0.001 * 3;
  v.target_displacement = {std::nextafter(0.1, 1.0)};
  v.target_velocity = {-1.0 / 3.0};
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encode(link.command(), v, bytes));
  FrameValues back;
  ASSERT_EQ(decode(link.command(), bytes.data(), bytes.size(), 1, back), FrameVerdict::kOk);
  EXPECT_EQ(back.target_displacement[0], v.target_displacement[0]);
  EXPECT_EQ(back.target_velocity[0], v.target_velocity[0]);
  EXPECT_EQ(back.time, v.time);
  EXPECT_EQ(back.counter, 7);
}

TEST(Frame, WrongSizeAndNonFiniteValuesAreRefused) {
  const config::ControllerLink link = test::controller_link(1, 2);
  FrameValues v;
  v.measured_displacement = {0.01};
  v.measured_force = {100.0};
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encode(link.feedback(), v, bytes));
  FrameValues back;
  EXPECT_EQ(decode(link.feedback(), bytes.data(), bytes.size() - 1, 1, back),
            FrameVerdict::kWrongSize);
  bytes.push_back(0);
  EXPECT_EQ(decode(link.feedback(), bytes.data(), bytes.size(), 1, back), FrameVerdict::kWrongSize);
  bytes.pop_back();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(bytes.data() + 16, &nan, 8);  // the force
  EXPECT_EQ(decode(link.feedback(), bytes.data(), bytes.size(), 1, back), FrameVerdict::kNonFinite);
}

// A controller's spare words are whatever its model leaves there: a NaN or an infinity in a
// PADDING field is not a measured value, so the frame is accepted and its values read.
TEST(Frame, PaddingIsNeverReadAsAValue) {
  const config::FrameLayout l = layout(
      "fields { role: COUNTER type: U32 } "
      "fields { name: \"spare\" role: PADDING type: F64 } "
      "fields { role: MEASURED_DISPLACEMENT type: F64 } "
      "fields { name: \"spare2\" role: PADDING type: F32 byte_order: ORDER_BIG } "
      "fields { role: MEASURED_FORCE type: F64 }");
  ASSERT_NO_THROW(runtime::check_frame_layout(l, 1, Direction::kFeedback, "feedback"));
  FrameValues v;
  v.counter = 9;
  v.measured_displacement = {0.004};
  v.measured_force = {-250.0};
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(encode(l, v, bytes));
  ASSERT_EQ(bytes.size(), 32u);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(bytes.data() + 4, &nan, 8);  // spare
  const std::uint8_t big_endian_infinity[4] = {0x7F, 0x80, 0x00, 0x00};
  std::memcpy(bytes.data() + 20, big_endian_infinity, 4);  // spare2
  FrameValues back;
  ASSERT_EQ(decode(l, bytes.data(), bytes.size(), 1, back), FrameVerdict::kOk);
  EXPECT_EQ(back.counter, 9);
  EXPECT_EQ(back.measured_displacement[0], 0.004);
  EXPECT_EQ(back.measured_force[0], -250.0);
  // The same NaN in a field that carries a value still refuses the frame.
  std::memcpy(bytes.data() + 12, &nan, 8);  // the measured displacement
  EXPECT_EQ(decode(l, bytes.data(), bytes.size(), 1, back), FrameVerdict::kNonFinite);
}

TEST(Frame, AValueThatDoesNotFitItsTypeIsNotEncoded) {
  const config::FrameLayout l = layout(
      "fields { role: COUNTER type: U32 } fields { role: TARGET_DISPLACEMENT type: I32 "
      "scale: 1e-9 }");
  FrameValues v;
  v.target_displacement = {3.0};  // 3e9 nm: beyond i32
  v.target_velocity = {0.0};
  std::vector<std::uint8_t> bytes;
  EXPECT_FALSE(encode(l, v, bytes));
  v.target_displacement = {0.002};
  EXPECT_TRUE(encode(l, v, bytes));
  v.counter = -1;  // a U32 counter cannot be negative
  EXPECT_FALSE(encode(l, v, bytes));
}

}  // namespace
}  // namespace rths::controller_node
