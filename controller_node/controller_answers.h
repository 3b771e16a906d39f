#pragma once
// A lab's real-time controller as a node's answer source (runtime/node/answer_source.h): each
// command goes out as a UDP frame, each judged frame back is the answer to the step it commanded.
// Input: Command.time (s), drift (m) and drift_velocity (m/s), one per hosted actuator. Output:
// Feedback.realised (m, the controller's measured drift) and force (N), same order, the
// layout's diagnostics, the frame's round trip (s) and the controller's status.
//
// Threads (answer_source.h): dispatch() packs the step's command frame and sends it at once (a
// non-blocking send on a connected UDP socket), allocating nothing once warm; wait() blocks in
// ppoll on the socket only; next() reads every queued datagram without blocking, judges it
// (ControllerExchange) and returns each accepted answer for the step its frame commanded, so
// several frames may be in flight and a controller 2 ms behind costs 2 ms, not a backlog. It
// also expires frames past the reply timeout (a staleness limit) and, once held or stopped, runs
// the hold: HOLD frames until the controller answers held or the hold time passes, then (stopped)
// one STOP frame; after it nothing is sent, and whatever the controller still sends is read and
// logged. A command of the wrong size, or a frame that cannot be sent, is the next fault.

#include <memory>
#include <string>
#include <vector>

#include "controller_node/controller_exchange.h"
#include "runtime/node/answer_source.h"

namespace rths::controller_node {

class ControllerAnswers final : public runtime::AnswerSource {
 public:
  // `label` names the node in log lines.
  ControllerAnswers(std::unique_ptr<ControllerExchange> exchange, std::string label);

  void dispatch(std::int64_t step, const runtime::Command& command) override;
  void wait(std::int64_t deadline_ns) override { exchange_->wait(deadline_ns); }
  Next next(runtime::Feedback& feedback) override;
  void hold() override;
  void stop() override;
  bool rested() const override { return hold_done_ && (!stop_requested_ || stop_sent_); }

  ControllerExchange& exchange() { return *exchange_; }

 private:
  std::unique_ptr<ControllerExchange> exchange_;
  std::string label_;
  std::vector<double> drift_, velocity_;  // m, m/s: the command being packed
  std::string dispatch_fault_;
  bool hold_done_ = false, stop_requested_ = false, stop_sent_ = false;
};

}  // namespace rths::controller_node
