#pragma once
// Controller node: drives a lab's real-time controller (Simulink Real-Time, LabVIEW RT, dSPACE...)
// over fixed UDP frames, and answers the coordinator as an actuator emulator does, so the
// coordinator cannot tell the two apart. Input: Command.time (s), drift (m) and drift_velocity
// (m/s), one per hosted actuator. Output: Feedback.realised (m, the controller's measured drift)
// and force (N), same order, plus the frame's round trip (s) and the controller's status.
//
// What the service adds to a node (runtime/node/node_service.h): configure() checks the
// assignment's controller link and builds its answer source (controller_answers.h: the link,
// its threads and its hold), and each heartbeat carries the link's report.
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

#include "controller_node/controller_answers.h"
#include "runtime/node/node_service.h"

namespace rths::controller_node {

class ControllerService final : public runtime::NodeService {
 public:
  ControllerService(std::int32_t node_id, std::string expected_run_id);
  runtime::ControllerReport report() const;

 protected:
  int configure(const runtime::Assign& assign) override;
  runtime::AnswerSource* answer_source() override { return answers_.get(); }
  void fill_heartbeat(runtime::Heartbeat& heartbeat) const override;

 private:
  std::unique_ptr<ControllerAnswers> answers_;
};

}  // namespace rths::controller_node
