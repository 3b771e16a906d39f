#pragma once
// Controller node: drives a lab's real-time controller (Simulink Real-Time, LabVIEW RT, dSPACE...)
// over fixed UDP frames, and answers the coordinator as an actuator emulator does, so the
// coordinator cannot tell the two apart. Input: Command.time (s), drift (m) and drift_velocity
// (m/s), one per hosted actuator. Output: Feedback.realised (m, the controller's measured drift)
// and force (N), same order, plus the frame's round trip (s) and the controller's status.
//
// Threads (an asynchronous NodeService: runtime/node/node_service.h):
//   command   the DDS receive thread (or the node loop, behind a receive lag): dispatch() packs
//             the step's command frame and sends it at once (a non-blocking send on a connected
//             UDP socket); it never waits for an answer and allocates nothing once warm.
//   answers   the node loop's answer thread: wait_for_answers() blocks in ppoll on the socket
//             only (no lock, nothing else); next_answer(), under the node's lock, reads every
//             queued datagram without blocking, judges it (ControllerExchange) and returns each
//             accepted answer for the step its frame commanded, so several frames may be in
//             flight and a controller 2 ms behind costs 2 ms, not a backlog. It also expires
//             frames past the reply timeout (a staleness limit) and, once held or stopped,
//             runs the hold.
// A refused answer, or lost frames beyond the window -> the node holds on its own and answers
// HOLD naming the cause (nothing refused is ever applied).
// HOLD (from the coordinator, its own watchdog, or a refused answer) -> HOLD frames (status 1)
// carrying the position to hold (the newest measured drift), repeated every dt until the
// controller answers one with status 1 (held) or controller.hold_time_ms passes. STOP -> the same
// hold first, then one STOP frame (status 2); the final heartbeat (the link report) follows.
// Limits: |measured drift| <= 2 x deployment.limits.max_displacement (a drift spans two DOFs),
// |force| <= controller.max_force (0 = no limit); rates and tracking error as configured
// (controller_exchange.h). The reply timeout is at most the answer window in real time (a
// frame older than it is never applied; by default half of it, at least one dt) and
// step_timeout in lockstep (by default 1 s). Real time: the node holds after the lost frames that
// fit in the window (window - reply timeout - window / 8, in steps, at least 1), before the
// coordinator's own window on the answers' age passes, so the HOLD names the controller.

#include <memory>

#include "controller_node/controller_exchange.h"
#include "runtime/node/node_service.h"

namespace rths::controller_node {

class ControllerService final : public runtime::NodeService {
 public:
  ControllerService(std::int32_t node_id, std::string expected_run_id);
  runtime::ControllerReport report() const;

 protected:
  int configure(const runtime::Assign& assign) override;
  void compute(const runtime::Command& command, runtime::Feedback& feedback) override;
  bool answers_asynchronously() const override { return true; }
  void dispatch(std::int64_t step, const runtime::Command& command) override;
  void wait_for_answers(std::int64_t deadline_ns) override;
  Answered next_answer(runtime::Feedback& feedback) override;
  bool rested() const override;
  void on_hold() override;
  void on_stop() override;
  void fill_heartbeat(runtime::Heartbeat& heartbeat) const override;

 private:
  std::unique_ptr<ControllerExchange> exchange_;
  std::vector<double> drift_, velocity_;
  std::string dispatch_fault_;
  bool hold_done_ = false, stop_requested_ = false, stop_sent_ = false;
};

}  // namespace rths::controller_node
