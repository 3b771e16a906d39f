#pragma once
// Controller emulator: stands in for a lab's real-time controller in tests and dry runs. It
// speaks a CONTROLLER node's UDP frames (the node's `controller` link, seen from the other end:
// it binds peer_address:peer_port and answers to local_address:local_port) and runs the same
// actuator models as the actuator emulator: an in-process actuator_emulator::ActuatorService
// built from the same study, case and node (the case's delay stages, the servo, the emulated
// specimen), so a lockstep run through a controller node equals the in-process run bit for bit
// when the frames carry f64 at scale 1.
//
// step(frame) -> the feedback frame, or nothing:
//   a command frame, status RUN    -> the actuators take it as the next step (answer each command
//                                     frame once: realised drift, measured force, counter echoed,
//                                     status 0; status 1 when the actuators hold)
//   status HOLD (1)                 -> the actuators hold (ramping to rest at the rate limit) and
//                                     the frame is logged; no answer
//   status STOP (2)                 -> stopped(); no answer
//   wrong size, a value not finite  -> counted (rejected), no answer
// Lockstep and real time alike answer each frame at once (the actuators' servo periods run in
// simulated time inside the step). `answer_frames` >= 0: answer that many command frames, then
// keep reading (HOLD and STOP are still logged) but never answer: a controller gone silent.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "actuator_emulator/actuator_service.h"
#include "rths/proto/config.pb.h"

namespace rths::controller_emulator {

struct EmulatorCounts {
  std::uint64_t commands = 0, answered = 0, holds = 0, stops = 0, rejected = 0;
};

class ControllerEmulator {
 public:
  // Throws std::invalid_argument naming the problem (no such node, not a CONTROLLER, a bad
  // layout, the actuators refusing their part).
  ControllerEmulator(const config::Study& study, const std::filesystem::path& base_dir,
                     const std::string& case_name, int node_id, std::int64_t answer_frames = -1);
  ~ControllerEmulator();

  std::optional<std::vector<std::uint8_t>> step(const std::uint8_t* data, std::size_t size);
  bool stopped() const { return counts_.stops > 0; }
  const EmulatorCounts& counts() const { return counts_; }
  const config::ControllerLink& link() const { return link_; }

 private:
  config::ControllerLink link_;
  int actuators_ = 0;
  std::int64_t answer_frames_ = -1;
  std::int64_t step_ = 0;  // the actuators' step: one per command frame taken
  std::unique_ptr<actuator_emulator::ActuatorService> service_;
  EmulatorCounts counts_;
  bool holding_ = false;
};

// The socket loop: binds the link's peer end, answers frames until STOP (returns 0) or until no
// frame came for `idle_timeout` s (returns 1). Logs every HOLD and STOP frame it receives.
int serve(ControllerEmulator& emulator, double idle_timeout);

}  // namespace rths::controller_emulator
