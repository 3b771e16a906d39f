#pragma once
// How old the answer a real-time step applies may be, and how old they were.
//
// AnswerWindow (per node, fixed once built): the oldest answer a step may apply, in steps of dt.
//   window(t) = max_missed_answers                           (the deployment's answer window)
//             + ceil(injected(t) / dt)                        (the lag the node's link injects)
//   injected(t) = sum over receive_lag and send_lag of  one_way_delay + 5 jitter
//                 + network.spike_delay + network.drift_rate t            (s; t simulated, s)
// An answer older than window(t) counts as missing: the coordinator stops the run (HOLD) rather
// than apply it, whatever the node kind, so no force older than the window reaches the
// integrator. Before a node's first answer (nothing old is applied: the specimen is at rest) the
// coordinator allows the liveliness timeout instead, if longer (exchange.cpp). A link whose real
// lag is longer than the one injected (a real network) needs its answer_window_ms to cover it.
//
// AnswerAgeTally: step(age) counts one real-time step's age (steps: the step commanded minus
// the step its newest answer answers) in fixed bins (no allocation); summary() gives the median,
// p99 and max in steps (ms = steps x dt), with the window and dt.

#include <array>
#include <cstdint>

#include "rths/proto/deployment.pb.h"
#include "rths/proto/runtime.pb.h"

namespace rths::coordinator {

class AnswerWindow {
 public:
  AnswerWindow(const config::Deployment& deployment, const config::NodeSpec& spec, double dt);
  std::int64_t steps(double time) const;  // time: s, simulated

 private:
  double dt_, fixed_ = 0.0, drift_rate_ = 0.0;  // s, s, s per s
  int missed_ = 0;
};

class AnswerAgeTally {
 public:
  static constexpr std::size_t kBins = 4096;  // ages of kBins - 1 steps and more share the last

  void step(std::int64_t age);
  runtime::AnswerAge summary(double window_steps, double dt) const;

 private:
  std::array<std::uint64_t, kBins> counts_{};
  std::uint64_t steps_ = 0;
  std::int64_t max_ = 0;
};

}  // namespace rths::coordinator
