#include "opensees_site/protocol.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rths::opensees {
namespace {

// What genericClient sends for n basic DOFs and a frame size.
SizeMessage sizes(int n, int frame) {
  SizeMessage m{};
  m[0] = m[1] = m[2] = m[8] = n;
  m[4] = 1;
  m[10] = frame;
  return m;
}

std::string refusal(const SizeMessage& m, int n, int expected = 0) {
  try {
    check_size_message(m, n, expected);
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "";
}

TEST(Protocol, GenericClientsSizeMessageIsAccepted) {
  EXPECT_EQ(check_size_message(sizes(2, 256), 2, 0), 256);
  EXPECT_EQ(check_size_message(sizes(2, 8), 2, 8), 8);  // 1 + 3n + 1
  EXPECT_EQ(minimum_frame_size(2), 8);
  EXPECT_EQ(minimum_frame_size(6), 36);  // n^2
}

TEST(Protocol, WrongSizeMessagesAreRefusedNamingTheSlot) {
  EXPECT_NE(refusal(sizes(1, 256), 2).find("slot 0 (disp size) is 1, expected 2"),
            std::string::npos);
  SizeMessage m = sizes(2, 256);
  m[4] = 0;
  EXPECT_NE(refusal(m, 2).find("slot 4 (time size) is 0"), std::string::npos);
  m = sizes(2, 256);
  m[8] = 3;
  EXPECT_NE(refusal(m, 2).find("slot 8 (force size)"), std::string::npos);
  EXPECT_NE(refusal(sizes(2, 7), 2).find("7 doubles, allowed 8 to 65536"), std::string::npos);
  EXPECT_NE(refusal(sizes(2, 1 << 20), 2).find("allowed 8 to 65536"), std::string::npos);
  EXPECT_NE(refusal(sizes(2, 256), 2, 128).find("opensees.frame_size is 128"), std::string::npos);
}

TEST(Protocol, ActionsAreKnownByTheirCodes) {
  EXPECT_EQ(action_of(3.0), Action::kSetTrialResponse);
  EXPECT_EQ(action_of(99.0), Action::kDie);
  EXPECT_TRUE(expects_answer(Action::kGetForce));
  EXPECT_TRUE(expects_answer(Action::kGetMass));
  EXPECT_FALSE(expects_answer(Action::kCommitState));
  EXPECT_FALSE(expects_answer(Action::kSetTrialResponse));
  for (double bad : {0.0, 7.0, 3.5, -3.0, std::nan("")})
    EXPECT_THROW(action_of(bad), ProtocolError) << bad;
}

TEST(Protocol, NonFiniteTrialsAreRefusedNamingWhatTheSlotHolds) {
  std::vector<double> frame(256, 0.0);
  frame[0] = 3;
  EXPECT_NO_THROW(check_trial_frame(frame, 2));
  frame[4] = INFINITY;  // vel of basic DOF 2
  try {
    check_trial_frame(frame, 2);
    FAIL();
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("slot 4 (vel of basic DOF 2)"), std::string::npos)
        << e.what();
  }
  frame[4] = 0;
  frame[7] = std::nan("");  // time
  EXPECT_THROW(check_trial_frame(frame, 2), ProtocolError);
}

}  // namespace
}  // namespace rths::opensees
