#pragma once
// Wall-clock lag a node injects on one direction of its link, and lag statistics.
//
// LagInjector (config LinkLag): for a message taken off the wire at time t (ns, any clock),
//   delay  = max(0, one_way_delay + jitter * N(0,1))   (std::mt19937_64 seeded with `seed`)
//   lost   with probability `loss` (then no release time)
//   release = max(t + delay + extra, previous release)  -- FIFO: a link does not reorder.
// The network emulation (config NetworkEmulation), on a command of step k (time k dt) only:
//   extra   = drift_rate k dt + (spike_delay when k % spike_every < spike_steps), s
//   dropped when drop_first_step <= k < drop_first_step + drop_steps
// and unreported: last_delay() = release - t - extra (what goes into the answer's injected_lag).
// Computed by core::LinkWayLag, the one lag algorithm the in-process link also runs.
// Deterministic for a given seed and arrival sequence.
//
// LagStats: count, mean, median, p99, max of a set of lags (s).

#include <cstdint>
#include <optional>
#include <vector>

#include "core/link_answers.h"
#include "rths/proto/deployment.pb.h"

namespace rths::runtime {

class LagInjector {
 public:
  // dt: s, the run's step, which times the network emulation.
  explicit LagInjector(const config::LinkLag& spec, double dt = 0.0);
  // Release time (ns) for a message arriving at `arrival_ns`, or nullopt when it is lost.
  // command_step: the step of the command the message is (receive side) or answers (send side);
  // < 0 for any other message, which the network emulation leaves alone.
  std::optional<std::int64_t> schedule(std::int64_t arrival_ns, std::int64_t command_step = -1) {
    return lag_.release(arrival_ns, command_step);
  }
  // s, of the last scheduled message: the reported lag (without the network emulation's extra).
  double last_delay() const { return lag_.last_delay(); }
  bool active() const { return lag_.active(); }

 private:
  // The one lag algorithm, shared with the in-process link (core/link_answers.h), so a case's
  // link in process and a node injecting the same LinkLag draw the same sequence.
  core::LinkWayLag lag_;
};

struct LagSummary {
  std::size_t count = 0;
  double mean = 0, median = 0, p99 = 0, max = 0;  // s
};

LagSummary summarize(std::vector<double> lags);

}  // namespace rths::runtime
