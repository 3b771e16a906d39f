#pragma once
// Will a deployment's fail-safe and overrun tolerance hold on this machine, and what to change.
//
// Inputs: the measured wake-up lateness (LatencyStats), the kernel facts (for the fixes) and the
// deployment at its dt (FailSafeInput). A healthy run is stopped falsely when some process stalls
// longer than the fail-safe allows: a stall of s silences a link for s plus up to one step (the
// answer or command that was due), and a link with jitter sigma each way (FIFO) delivers an answer
// up to 4 sqrt(2) sigma after its neighbour. So a window W (ms) is crossed by stalls longer than
//     x(W) = W - dt - 4 sqrt(2) sigma_max.
// The rate of stalls longer than x, r(x) per minute, is the measured one where at least 3 were
// seen; beyond, the exponential tail fitted (least squares on log r) to the measured rates from
// 0.5 ms up to the last threshold with 3 stalls, and 2 x the longest stall measured when fewer
// than two such thresholds exist. Probability that a run of T minutes is stopped falsely:
//     P(W) = 1 - exp(-r(x(W)) T).
// Required window: the smallest whole number of steps k with P(k dt) <= 1 % and x(k dt) >= the
// longest stall measured (the run's windows are whole steps), stated in ms as
// runtime::window_ms_of_steps(k, dt). A window shorter than it does not hold.
// Overruns: predicted fraction = LatencyStats::overrun_fraction(work), work = the wait for answers
// (feedback_wait_fraction x dt) when the loop waits for any node, else 5 % of dt; it holds when
// <= max_overrun_fraction (a negative tolerance is never checked). The fix offered is twice the
// predicted fraction, up to 5 %; beyond that the machine cannot run the rate in real time now.
// refused(): a real-time run under this verdict refuses to start unless --accept-platform.

#include <string>
#include <vector>

#include "rt_check/latency.h"
#include "rt_check/probe.h"
#include "rths/proto/deployment.pb.h"

namespace rths::rt_check {

inline constexpr double kFalseStopTarget = 0.01;  // per run

struct FailSafeInput {
  double dt = 0.0;                   // s
  double run_seconds = 0.0;          // s of the run judged
  int answer_steps = 3;              // coordinator: max consecutive steps without an answer
  int watchdog_steps = 3;            // emulator: command watchdog, periods
  bool watchdog_defaulted = false;   // neither watchdog field set: it follows the answer window
  std::string priority_text;         // runtime::realtime_priority_text of the deployment
  double max_link_jitter = 0.0;      // s, largest jitter (sigma) of any node's link, either way
  double overrun_tolerance = 0.001;  // < 0: not checked
  double step_work = 0.0;            // s after the wake-up before the step's commands are out
  std::vector<int> cpus;             // the CPUs the run uses (the loop's first when pinned)
  int loop_cpu = -1;                 // pinned loop CPU, -1 = unpinned
};

// From a study's deployment (runtime/node/plan.h defaults). `cpus_allowed`: this process's CPUs.
FailSafeInput failsafe_input(const config::Deployment& deployment, double dt, double run_seconds,
                             const std::vector<int>& cpus_allowed);

struct FailSafeVerdict {
  double window_ms = 0.0;  // the shorter of the deployment's two windows
  double required_window_ms = 0.0;
  int required_steps = 0;               // k above; required_window_ms is its ms
  double false_stop_probability = 0.0;  // per run, at the deployment's window
  bool window_holds = false;
  double predicted_overrun_fraction = 0.0;
  bool overruns_hold = false;
  std::vector<std::string> findings;  // what holds and what does not, with the numbers
  std::vector<std::string> fixes;     // what to change, most direct first
  bool refused() const { return !window_holds || !overruns_hold; }
  std::string refusal() const;  // findings and fixes as one message
};

// Rate (per minute) of stalls longer than x (s) with the tail extrapolation above.
double stall_rate_per_minute(const LatencyStats& stats, double x);

FailSafeVerdict judge_failsafe(const LatencyStats& stats, const PlatformFacts& facts,
                               const FailSafeInput& input);

}  // namespace rths::rt_check
