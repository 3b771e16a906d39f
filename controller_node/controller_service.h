#pragma once
// Controller node: drives a lab's real-time controller (Simulink Real-Time, LabVIEW RT, dSPACE...)
// over fixed UDP frames, and answers the coordinator as an actuator emulator does, so the
// coordinator cannot tell the two apart. Input: Command.time (s), drift (m) and drift_velocity
// (m/s), one per hosted actuator. Output: Feedback.realised (m, the controller's measured drift)
// and force (N), same order, plus the frame's round trip (s) and the controller's status.
//
// Per COMMAND: one command frame (counter + 1, status RUN, the targets) and its answer, judged by
// ControllerExchange (controller_exchange.h): a rejected or missing answer is never applied.
//   the answer is refused (wrong size, counter repeated or never sent, not finite, beyond the
//   limits, status not running) or, lockstep, it does not come within the reply timeout
//       -> the node holds on its own and answers HOLD naming the cause instead of FEEDBACK.
//   real time, no answer in time -> no FEEDBACK this step (lost); max_missed_answers lost in a
//       row -> HOLD as above.
//   a frame from anyone but the configured peer -> counted, named, ignored.
// HOLD (from the coordinator, its own watchdog, or a refused answer) -> a command frame with
// status HOLD (1) and the newest targets goes to the controller, so the rig holds. STOP -> one
// with status STOP (2). The link report (ControllerReport) goes up in every heartbeat and is
// logged on STOP. Limits: |measured drift| <= 2 x deployment.limits.max_displacement (a drift
// spans two DOFs), |force| <= controller.max_force (0 = no limit).

#include <memory>

#include "controller_node/controller_exchange.h"
#include "runtime/node/node_service.h"

namespace rths::controller_node {

class ControllerService final : public runtime::NodeService {
 public:
  ControllerService(std::int32_t node_id, std::string expected_run_id);
  const runtime::ControllerReport& report() const;

 protected:
  int configure(const runtime::Assign& assign) override;
  void compute(const runtime::Command& command, runtime::Feedback& feedback) override;
  std::string failure() override;
  bool answered() const override { return answered_; }
  void on_hold() override;
  void on_stop() override;
  void fill_heartbeat(runtime::Heartbeat& heartbeat) const override;

 private:
  std::unique_ptr<ControllerExchange> exchange_;
  std::vector<double> drift_, velocity_;
  std::string fault_;
  bool answered_ = true;
};

}  // namespace rths::controller_node
