#include "rt_check/verdict.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "runtime/node/plan.h"

namespace rths::rt_check {
namespace {

constexpr double kGrid = 0.25e-3;    // s, thresholds of the tail fit
constexpr double kFitFrom = 0.5e-3;  // s, the tail starts here (below: ordinary timer jitter)
constexpr std::uint64_t kSeen = 3;   // stalls seen for a measured rate
constexpr double kMaxWindow = 60.0;  // s
constexpr double kMaxSensibleTolerance = 0.05;  // beyond, a "real-time" run is mostly late steps

// log r(x) = a + b x, least squares over the measured thresholds with >= kSeen stalls.
struct Tail {
  bool fitted = false;
  double a = 0.0, b = 0.0;
};

Tail fit_tail(const LatencyStats& stats) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (double x = kFitFrom; stats.count_over(x) >= kSeen; x += kGrid) {
    const double y = std::log(stats.stalls_per_minute(x));
    n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  Tail tail;
  const double denominator = n * sxx - sx * sx;
  if (n < 2 || denominator <= 0) return tail;
  tail.b = (n * sxy - sx * sy) / denominator;
  tail.a = (sy - tail.b * sx) / n;
  tail.fitted = tail.b < 0;
  return tail;
}

double rate_with(const LatencyStats& stats, const Tail& tail, double x) {
  if (stats.minutes() <= 0) return 0.0;
  if (stats.count_over(x) >= kSeen) return stats.stalls_per_minute(x);
  if (tail.fitted) return std::exp(tail.a + tail.b * x);
  // Too few stalls to fit a tail: assume one up to twice the longest measured.
  const double seen = static_cast<double>(std::max<std::uint64_t>(stats.count_over(x), 1));
  return x < 2.0 * stats.max() ? seen / stats.minutes() : 0.0;
}

void tuning_fixes(const PlatformFacts& facts, const FailSafeInput& in,
                  std::vector<std::string>& fixes) {
  if (in.loop_cpu < 0 && in.cpus.size() > 1)
    fixes.push_back("give the loop a CPU of its own: pin_loop: true loop_cpu: " +
                    std::to_string(in.cpus.back()));
  if (facts.isolated_cpus.empty())
    fixes.push_back(
        "keep the kernel's own work off the loop's CPU: isolcpus= and nohz_full= on the "
        "kernel command line, IRQ affinity away from it");
  if (!facts.realtime_kernel())
    fixes.push_back(
        "a PREEMPT_RT kernel (its wake-ups are late by tens of us, not ms; this one is " +
        facts.preemption + ")");
  if (facts.governor.find(':') != std::string::npos &&
      facts.governor.find("powersave") != std::string::npos)
    fixes.push_back("the performance CPU governor (now " + facts.governor + ")");
  if (!facts.dma_latency_holdable)
    fixes.push_back(
        "permission to hold /dev/cpu_dma_latency (run as root or give the group write access)");
}

// What to change in the deployment when the window or the overrun tolerance does not hold.
void add_deployment_fixes(const LatencyStats& stats, FailSafeVerdict& v) {
  if (!v.window_holds)
    v.fixes.push_back(
        fmt::format(
            "answer_window_ms: {:.3f} command_watchdog_ms: {:.3f} in the deployment (a real "
            "fault is then held within {:.3f} ms instead of {:.2f} ms, ",
            v.required_window_ms, v.required_window_ms, v.required_window_ms, v.window_ms) +
        fmt::format("plus any stall at that moment: up to {:.2f} ms measured here)",
                    1e3 * stats.max()));
  if (!v.overruns_hold && v.predicted_overrun_fraction <= kMaxSensibleTolerance / 2)
    v.fixes.push_back(fmt::format("max_overrun_fraction: {:.4f} (twice the predicted fraction)",
                                  2.0 * v.predicted_overrun_fraction));
  else if (!v.overruns_hold)
    v.fixes.push_back(
        fmt::format("no overrun tolerance makes this a real-time test: {:.1f} % of the steps "
                    "would overrun; run at a lower rate or on a quieter machine",
                    100.0 * v.predicted_overrun_fraction));
}

}  // namespace

double stall_rate_per_minute(const LatencyStats& stats, double x) {
  return rate_with(stats, fit_tail(stats), x);
}

FailSafeInput failsafe_input(const config::Deployment& d, double dt, double run_seconds,
                             const std::vector<int>& cpus_allowed) {
  FailSafeInput in;
  in.dt = dt;
  in.run_seconds = run_seconds;
  in.answer_steps = runtime::max_missed_answers(d, dt);
  in.watchdog_steps = runtime::command_watchdog_periods(d, dt);
  in.watchdog_defaulted = !(d.command_watchdog_ms() > 0) && d.command_watchdog_periods() <= 0;
  in.priority_text = runtime::realtime_priority_text(d);
  in.overrun_tolerance = runtime::max_overrun_fraction(d);
  bool awaits = d.nodes().empty();  // default nodes inject no lag: their answers are awaited
  for (const config::NodeSpec& node : d.nodes()) {
    in.max_link_jitter =
        std::max({in.max_link_jitter, node.receive_lag().jitter(), node.send_lag().jitter()});
    awaits = awaits || runtime::awaits_answers(d, node, dt);
  }
  in.step_work = awaits ? runtime::feedback_wait_fraction(d) * dt : 0.05 * dt;
  std::set<int> cpus(cpus_allowed.begin(), cpus_allowed.end());
  if (d.pin_loop() && d.loop_cpu() >= 0) {
    in.loop_cpu = d.loop_cpu();
    cpus.insert(in.loop_cpu);
  }
  in.cpus.assign(cpus.begin(), cpus.end());
  return in;
}

FailSafeVerdict judge_failsafe(const LatencyStats& stats, const PlatformFacts& facts,
                               const FailSafeInput& in) {
  FailSafeVerdict v;
  const Tail tail = fit_tail(stats);
  const double allowance = in.dt + 4.0 * std::sqrt(2.0) * in.max_link_jitter;
  const double minutes = in.run_seconds / 60.0;
  const auto probability = [&](double window) {
    return 1.0 - std::exp(-rate_with(stats, tail, std::max(0.0, window - allowance)) * minutes);
  };
  const int steps = std::min(in.answer_steps, in.watchdog_steps);
  const double window = steps * in.dt;
  v.window_ms = 1e3 * window;
  v.false_stop_probability = probability(window);
  // The run's windows are whole steps, so the search is too: what it names is what runs.
  int required = 1;
  const auto too_short = [&](int k) {
    return k * in.dt - allowance < stats.max() || probability(k * in.dt) > kFalseStopTarget;
  };
  while (required * in.dt < kMaxWindow && too_short(required)) ++required;
  v.required_steps = required;
  v.required_window_ms = runtime::window_ms_of_steps(required, in.dt);
  v.window_holds = steps >= v.required_steps;
  v.predicted_overrun_fraction = stats.overrun_fraction(in.step_work);
  v.overruns_hold =
      in.overrun_tolerance < 0 || v.predicted_overrun_fraction <= in.overrun_tolerance;

  const double x = std::max(0.0, window - allowance);
  const std::string source = stats.count_over(x) >= kSeen ? "measured"
                             : tail.fitted                ? "tail fit"
                                                          : "bound";
  v.findings.push_back(
      fmt::format("windows: the coordinator's answer window {} steps ({:.2f} ms); the command "
                  "watchdog of the actuator emulators and controller nodes {} periods ({:.2f} "
                  "ms",
                  in.answer_steps, 1e3 * in.answer_steps * in.dt, in.watchdog_steps,
                  1e3 * in.watchdog_steps * in.dt) +
      (in.watchdog_defaulted ? ", unset: the answer window)" : ")") +
      "; real-time threads: " + in.priority_text);
  v.findings.push_back(fmt::format("fail-safe window {:.2f} ms ({} steps at {:.0f} Hz): stalls "
                                   "longer than {:.2f} ms come ",
                                   v.window_ms, steps, 1.0 / in.dt, 1e3 * x) +
                       fmt::format("{:.3g} per minute (", rate_with(stats, tail, x)) + source +
                       fmt::format("); a {:.1f} s run is stopped falsely with probability {:.3g} %",
                                   in.run_seconds, 100.0 * v.false_stop_probability));
  v.findings.push_back(
      fmt::format("required: {:.3f} ms ({} steps) for <= 1 % false stops; the longest stall "
                  "measured was {:.2f} ms: ",
                  v.required_window_ms, v.required_steps, 1e3 * stats.max()) +
      (v.window_holds ? "the window holds" : "the window does NOT hold"));
  v.findings.push_back(
      fmt::format("predicted overruns {:.3f} % of steps against max_overrun_fraction {:.3f} %: ",
                  100.0 * v.predicted_overrun_fraction, 100.0 * in.overrun_tolerance) +
      (in.overrun_tolerance < 0 ? "not checked"
       : v.overruns_hold        ? "holds"
                                : "does NOT hold"));
  add_deployment_fixes(stats, v);
  if (v.refused()) tuning_fixes(facts, in, v.fixes);
  return v;
}

std::string FailSafeVerdict::refusal() const {
  std::string out;
  for (const std::string& f : findings) out += f + "\n";
  if (!fixes.empty()) out += "to change:\n";
  for (const std::string& f : fixes) out += "  - " + f + "\n";
  return out;
}

}  // namespace rths::rt_check
