#include "opensees_site/protocol.h"

#include <algorithm>
#include <cmath>

namespace rths::opensees {

int minimum_frame_size(int basic_dofs) {
  return std::max(1 + 3 * basic_dofs + 1, basic_dofs * basic_dofs);
}

int check_size_message(const SizeMessage& m, int basic_dofs, int expected_frame_size) {
  // What genericClient's setupConnection() puts in each slot.
  const std::array<std::int32_t, kSizeMessageInts - 1> want{
      basic_dofs, basic_dofs, basic_dofs, 0, 1, 0, 0, 0, basic_dofs, 0};
  static const char* const what[] = {"disp size",  "vel size", "accel size", "unused",
                                     "time size",  "unused",   "unused",     "unused",
                                     "force size", "unused"};
  for (int i = 0; i < kSizeMessageInts - 1; ++i)
    if (m[static_cast<std::size_t>(i)] != want[static_cast<std::size_t>(i)])
      throw ProtocolError("size message slot " + std::to_string(i) + " (" + what[i] + ") is " +
                          std::to_string(m[static_cast<std::size_t>(i)]) + ", expected " +
                          std::to_string(want[static_cast<std::size_t>(i)]) +
                          " (the element's basic DOFs are " + std::to_string(basic_dofs) +
                          " in this site's config)");
  const int frame = m[kSizeMessageInts - 1];
  const int minimum = minimum_frame_size(basic_dofs);
  if (frame < minimum || frame > kMaxFrameSize)
    throw ProtocolError("size message slot 10 (frame size) is " + std::to_string(frame) +
                        " doubles, allowed " + std::to_string(minimum) + " to " +
                        std::to_string(kMaxFrameSize));
  if (expected_frame_size > 0 && frame != expected_frame_size)
    throw ProtocolError("size message slot 10 (frame size) is " + std::to_string(frame) +
                        " doubles, but the config's opensees.frame_size is " +
                        std::to_string(expected_frame_size));
  return frame;
}

Action action_of(double slot0) {
  static constexpr int kCodes[] = {3, 5, 10, 12, 13, 14, 15, 99};
  for (int code : kCodes)
    if (slot0 == static_cast<double>(code)) return static_cast<Action>(code);
  throw ProtocolError("unknown action code " + std::to_string(slot0) +
                      " in slot 0 (served: 3, 5, 10, 12, 13, 14, 15, 99)");
}

const char* action_name(Action action) {
  switch (action) {
    case Action::kSetTrialResponse: return "setTrialResponse";
    case Action::kCommitState: return "commitState";
    case Action::kGetForce: return "getForce";
    case Action::kGetInitialStiff: return "getInitialStiff";
    case Action::kGetTangentStiff: return "getTangentStiff";
    case Action::kGetDamp: return "getDamp";
    case Action::kGetMass: return "getMass";
    case Action::kDie: return "DIE";
  }
  return "?";
}

bool expects_answer(Action action) {
  return action != Action::kSetTrialResponse && action != Action::kCommitState &&
         action != Action::kDie;
}

void check_trial_frame(const std::vector<double>& frame, int n) {
  static const char* const kinds[] = {"disp", "vel", "accel"};
  for (int slot = 1; slot <= 3 * n + 1; ++slot) {
    const double x = frame[static_cast<std::size_t>(slot)];
    if (std::isfinite(x)) continue;
    const std::string what = slot == 3 * n + 1
                                 ? std::string("time")
                                 : std::string(kinds[(slot - 1) / n]) + " of basic DOF " +
                                       std::to_string((slot - 1) % n + 1);
    throw ProtocolError("setTrialResponse slot " + std::to_string(slot) + " (" + what + ") is " +
                        std::to_string(x) + "; only finite values drive an actuator");
  }
}

}  // namespace rths::opensees
