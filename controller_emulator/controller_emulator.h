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
//   status HOLD (1)                 -> the actuators hold (ramping to rest at the rate limit), the
//                                     first is logged, and each is answered at once: status HOLD
//                                     (held) and the held position, force 0
//   status STOP (2)                 -> stopped(); no answer
//   wrong size, a value not finite  -> counted (rejected), no answer
// `answer_frames` >= 0: answer that many command frames, then keep reading (HOLD and STOP are
// still logged) but never answer: a controller gone silent.
//
// Two clocks, chosen by the study (the same as an actuator emulator's servo loop):
//   answer per frame (lockstep, or a servo no faster than the integrator): each command frame is
//     one integrator step of the actuators, their servo periods run in simulated time inside it,
//     and the frame is answered with that step's output. Deterministic: equals in process.
//   paced (deployment REAL_TIME and study.servo.rate an integer N > 1 times the integrator's
//     rate, e.g. 4096 Hz at dt = 1/1024 s): the plant runs on its own clock. A command frame only
//     loads the actuators' servo targets and is answered at once with the plant's newest state;
//     tick(overrun), called every plant_period() s (serve() paces it on CLOCK_MONOTONIC with the
//     deployment's wait policy), steps every actuator one servo period (dt / N) and keeps the
//     realised drift (m) and measured force (N) it reached. Before the first command and while
//     holding the plant does not move (as the actuator emulator's servo loop). ticks and overruns
//     (a period begun past its deadline) are counted.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "actuator_emulator/actuator_service.h"
#include "controller_node/frame.h"
#include "rths/proto/config.pb.h"
#include "runtime/rt/wait_policy.h"

namespace rths::controller_emulator {

struct EmulatorCounts {
  std::uint64_t commands = 0, answered = 0, holds = 0, stops = 0, rejected = 0;
  std::uint64_t ticks = 0, overruns = 0;  // paced only: plant periods run, begun late
};

class ControllerEmulator {
 public:
  // Throws std::invalid_argument naming the problem (no such node, not a CONTROLLER, a bad
  // layout, the actuators refusing their part).
  ControllerEmulator(const config::Study& study, const std::filesystem::path& base_dir,
                     const std::string& case_name, int node_id, std::int64_t answer_frames = -1);
  ~ControllerEmulator();

  std::optional<std::vector<std::uint8_t>> step(const std::uint8_t* data, std::size_t size);
  // Paced only: one plant period; `overrun`: it began past its deadline.
  void tick(bool overrun);
  bool paced() const { return service_->streaming(); }
  double plant_period() const { return service_->streaming_period(); }  // s; 0 unless paced
  const runtime::WaitPolicy& wait_policy() const { return wait_policy_; }
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
  runtime::WaitPolicy wait_policy_;
  std::vector<double> plant_realised_, plant_force_;  // paced: m, N at the newest plant period
  // Takes the command frame's targets as the actuators' next step; false when they refuse it.
  bool command_actuators(const controller_node::FrameValues& in, runtime::Feedback& feedback);
  std::optional<std::vector<std::uint8_t>> held_answer(const controller_node::FrameValues& in);
};

// The socket loop: binds the link's peer end, answers frames until STOP (returns 0) or until no
// frame came for `idle_timeout` s (returns 1). Logs every HOLD and STOP frame it receives.
// Paced: the plant runs on a thread of its own, one tick() per plant period on absolute
// deadlines (runtime::Pacer); step() and tick() take turns under one lock. `answer_lag` (s, >= 0):
// each answer leaves that long after serve() read its command frame (the link's round-trip lag,
// as a network would add it; kernel netem is not needed); several answers may wait for their
// lag at once (frames in flight), each leaving its lag after its own frame was read.
// `answer_period` (s, >= 0): answers leave at least that far apart, in order (a controller
// slower than the host: with a period longer than dt it falls further behind every frame).
int serve(ControllerEmulator& emulator, double idle_timeout, double answer_lag = 0.0,
          double answer_period = 0.0);

}  // namespace rths::controller_emulator
