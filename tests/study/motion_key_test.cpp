// study/motion_key: against SHA-256 computed apart (Python's hashlib over
// struct.pack('<3d', 0.01, 1.0, -2.5)).
#include "study/motion_key.h"

#include <gtest/gtest.h>

namespace rths::study {
namespace {

TEST(MotionKeyTest, MotionKeyIsTheSha256OfDtThenTheSamplesAsDoubles) {
  core::GroundMotion motion{.name = "pulse", .dt = 0.01, .acceleration = {1.0, -2.5}};
  EXPECT_EQ(motion_key(motion), "ff8467ff882a8d40a8057e2023f4b453bba79df2a90602dc8e0d756986506a6c");
  motion.name = "another name";
  motion.description = "another description";
  EXPECT_EQ(motion_key(motion), "ff8467ff882a8d40a8057e2023f4b453bba79df2a90602dc8e0d756986506a6c")
      << "the key is the motion's numbers, not its labels";
  motion.dt = 0.005;
  EXPECT_NE(motion_key(motion), "ff8467ff882a8d40a8057e2023f4b453bba79df2a90602dc8e0d756986506a6c");
}

}  // namespace
}  // namespace rths::study
