#pragma once
// The coordinator: the integrator loop of a distributed hybrid test, over any transport.
// Its whole contract, faults and real-time safety included, is docs/coordinator.md.
//
// Ports   in:  the prepared study and deployment; a transport::Endpoint (DDS or in-process) on
//              which the nodes announce, answer COMMANDs with FEEDBACK and send heartbeats.
//         out: ASSIGN, COMMAND, HOLD and STOP messages; the run record (header, one entry per
//              step, events, footer); RunOutcome.
// Sequence start-up: every node announces, gets its Assign and reports READY (timeout names the
//          nodes missing). Each step: core::run_steps() with this class as its evaluator
//          (commands out, the step's answers in) and hooks (pacing before, record after).
//          Lockstep waits for every answer (simulated time, equal to in process bit for bit);
//          real time paces on absolute deadlines and uses the newest answer within
//          feedback_wait_fraction * dt.
// Outcome  ok only when the run did what it was for: not diverged, the one real-time verdict
//          passed (runtime::deadline_verdict: overruns within max_overrun_fraction, no streak
//          of them past the answer window, not more than half the steps), no fault (a silent,
//          late or forged node, limits, a record that cannot be written, a stop request), no
//          record entry lost. Every stop sends HOLD to the emulators and STOP to all, and
//          closes the record naming the reason and the node.
// Threads  run() is the loop thread; feedback is decoded on the transport's receive thread into
//          wait-free boxes; the record is written on its own writer thread. A step allocates
//          nothing once warm except for non-feedback messages and rare events.

#include <memory>

#include "coordinator/run_types.h"
#include "runtime/node/plan.h"
#include "study/study.h"
#include "transport/transport.h"

namespace rths::coordinator {

struct RunState;  // coordinator/state.h, internal to rths_coordinator

class Coordinator {
 public:
  // Throws std::invalid_argument for a deployment that does not fit the study, an implicit
  // integrator, or a dt beyond the stability limit.
  Coordinator(study::PreparedStudy prepared, transport::Endpoint& endpoint,
              CoordinatorOptions options);
  ~Coordinator();
  // Runs the whole test on the calling thread (the loop thread) and returns how it ended; never
  // throws for a fault of a node, the wire or the record (those end in the outcome). Blocks for
  // the run's length. Call once.
  RunOutcome run();
  const runtime::DeploymentPlan& plan() const { return plan_; }

 private:
  std::unique_ptr<RunState> state_;
  runtime::DeploymentPlan plan_;
};

}  // namespace rths::coordinator
