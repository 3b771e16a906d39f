#pragma once
// The loop a node process runs around a NodeService on a real transport, one pass at a time:
// keep time (announce, heartbeat, watchdogs) -> write what is due -> apply what is due -> wait
// for a message and take it; set-up on assignment, teardown when it returns.
//   announce every `announce_period` until assigned;
//   every message taken off the wire goes through the receive-lag injector, then the service,
//   then the send-lag injector (both from the node's spec in its Assign; FIFO, wall clock);
//   a heartbeat every heartbeat period once assigned;
//   returns 0 on STOP, 1 when the coordinator has been silent for the orphan timeout or when
//   nothing assigned it within `assign_timeout`.
//   an actuator emulator in real time holds on its own (command watchdog) when no command has
//   arrived for command_watchdog_periods x dt; before it judges, it gives its receive thread
//   kWatchdogGrace to deliver commands that waited while the process itself was descheduled.
// Wall-clock stamps are CLOCK_REALTIME (transport::realtime_ns); the servo and answer threads
// pace and wait on CLOCK_MONOTONIC (runtime/rt/clock.h monotonic_ns).
//
// Threads: four that run the node, sharing one mutex (the loop's `state`) over the service, the timers and the
// lag queues; each holds it only while it acts, never while it waits.
//   loop      the caller's thread: keep time, write and apply what is due, wait for a message
//             (lock released in the wait). Allocates per message it queues behind a lag, never
//             on the paths below.
//   receive   the transport's receive thread: with no lag injected, a COMMAND is handled inline
//             there (no thread switch per step); the reply is packed in the service's buffer
//             and sent at once (NodeService::handle(message, send): no allocation once warm).
//   servo     a streaming node only (servo faster than the integrator): one servo_tick() per
//             period, paced on CLOCK_MONOTONIC with the deployment's wait policy.
//   answers   a node with an answer source only (runtime/node/answer_source.h): waits on the
//             source without the lock (at most kAnswerPoll), then forwards what it answered.
//   set-up    while an ASSIGN builds the node's part (on the loop or receive thread, under
//   watcher   `state`): runtime/node/setup_progress.h's watcher logs the phase past 3 s; it
//             takes only its own mutex, never `state`, and is joined before READY is sent.
// realtime_priority raises the loop's thread before the servo and answer threads start (they
// inherit it) and names the transport's receive threads.

#include <chrono>

#include "runtime/node/node_service.h"
#include "transport/transport.h"

namespace rths::runtime {

inline constexpr std::chrono::microseconds kWatchdogGrace{200};

struct NodeLoopOptions {
  double announce_period = 0.1;  // s
  double assign_timeout = 30.0;  // s
};

int run_node(transport::Endpoint& endpoint, NodeService& service, const NodeLoopOptions& options);

}  // namespace rths::runtime
