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
// Wall-clock stamps are CLOCK_REALTIME (transport::realtime_ns).

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
