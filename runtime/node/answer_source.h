#pragma once
// Where a node's answers come from when they come on their own, not as compute()'s return: a
// lab's real-time controller behind a UDP link (controller_node/controller_answers.h) is one.
// A node with a source (NodeService::answer_source() non-null after configure()) dispatches each
// accepted COMMAND to it and never waits; the node loop's answer thread (node_loop.h, Threads)
// waits on the source and forwards what it answers as FEEDBACK, echoing the envelope of the step
// each answer names.
//
// Threads and locks: dispatch(), next(), hold(), stop() and rested() run under the node's lock;
// wait() runs without it and may touch only the source's own wake-up (a socket), never state the
// other four share. Units: deadlines and stamps are CLOCK_MONOTONIC ns (runtime/rt/clock.h monotonic_ns).
// Real time: no method allocates once warm (a fault's text aside); only wait() blocks.

#include <cstdint>
#include <string>

#include "rths/proto/runtime.pb.h"

namespace rths::runtime {

class AnswerSource {
 public:
  // What next() found: an answer (feedback filled) for `step`, a fault (the node holds, naming
  // it) or nothing more for now.
  struct Next {
    enum class Kind { kNone, kAnswer, kFault } kind = Kind::kNone;
    std::int64_t step = 0;  // kAnswer: the step it answers
    std::string fault;      // kFault: why, as the HOLD names it
  };

  virtual ~AnswerSource() = default;
  // Command path (the transport's receive thread, or the loop behind a receive lag), node lock
  // held: passes the step's command on at once; never waits. A failure to pass it on surfaces
  // as a fault from the next call of next().
  virtual void dispatch(std::int64_t step, const Command& command) = 0;
  // Answer thread, node lock NOT held: blocks until an answer may be ready or `deadline_ns`.
  virtual void wait(std::int64_t deadline_ns) = 0;
  // Answer thread, node lock held, never blocks: the next answer, fault or nothing. Once the node
  // holds or stops it brings the source to rest instead and returns kNone.
  virtual Next next(Feedback& feedback) = 0;
  // The node holds (a HOLD, its own watchdog, a fault): the source starts coming to rest.
  virtual void hold() = 0;
  // The node stops (STOP): the source comes to rest, then tells its end the run is over.
  virtual void stop() = 0;
  // Held or stopped: whether it has come to rest (the final heartbeat waits for it).
  virtual bool rested() const = 0;
};

}  // namespace rths::runtime
