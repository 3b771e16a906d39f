#pragma once
// The wire protocol of OpenSees' genericClient element (SRC/element/generic/GenericClient.cpp over
// SRC/actor/channel/TCP_Socket.cpp), as a server sees it. No I/O here: checks of what arrived.
//
//   size message  the client connects and sends first 11 native ints (host byte order, no
//                 endianness check): [0] [1] [2] = n (disp, vel, accel sizes), [4] = 1 (time),
//                 [8] = n (force), [10] = the frame size F >= max(1 + 3n + 1, n^2); the others 0.
//   frames        F native doubles each way. Client -> server: slot 0 the action code; for
//                 setTrialResponse slots 1..n disp (m), n+1..2n vel, 2n+1..3n accel, 3n+1 time (s).
//                 Server -> client (only for the actions that expect an answer): a force vector
//                 (slots 0..n-1, N) or an n x n matrix, column-major (slots 0..n^2-1); the rest 0.
//   actions       3 setTrialResponse (no answer), 5 commitState (no answer), 10 getForce (n),
//                 12 getInitialStiff, 13 getTangentStiff, 14 getDamp, 15 getMass (n x n),
//                 99 the client is done (its element is destroyed). The element sends no other.

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rths::opensees {

// A client broke the protocol: what it sent and why it is refused.
struct ProtocolError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class Action : int {
  kSetTrialResponse = 3,
  kCommitState = 5,
  kGetForce = 10,
  kGetInitialStiff = 12,
  kGetTangentStiff = 13,
  kGetDamp = 14,
  kGetMass = 15,
  kDie = 99,
};

inline constexpr int kSizeMessageInts = 11;
inline constexpr int kDefaultFrameSize = 256;  // genericClient's -dataSize default
inline constexpr int kMaxFrameSize = 65536;    // doubles; a larger announcement is refused

using SizeMessage = std::array<std::int32_t, kSizeMessageInts>;

// The smallest frame the element allows for n basic DOFs: max(1 + 3n + 1, n^2).
int minimum_frame_size(int basic_dofs);

// The frame size the message announces. Throws ProtocolError naming the slot, the value and what
// was expected: sizes that do not match `basic_dofs`, a frame size below the minimum or above
// kMaxFrameSize, or different from `expected_frame_size` when that is > 0.
int check_size_message(const SizeMessage& message, int basic_dofs, int expected_frame_size);

// The action in slot 0. Throws ProtocolError for a value that is not one of Action's codes.
Action action_of(double slot0);
const char* action_name(Action action);
// Whether the client waits for an answer frame after this action.
bool expects_answer(Action action);

// The trial's slots (1 .. 3n + 1) must be finite. Throws ProtocolError naming the slot and what it
// holds (disp/vel/accel of basic DOF i, or time).
void check_trial_frame(const std::vector<double>& frame, int basic_dofs);

}  // namespace rths::opensees
