#include "tests/support/real_time_run.h"

#include <cstdio>
#include <regex>

#include "runtime/node/controller_link.h"
#include "runtime/node/plan.h"

namespace rths::test {
namespace {

std::optional<double> number_after(const std::string& status, const std::regex& pattern) {
  std::smatch match;
  if (!std::regex_search(status, match, pattern)) return std::nullopt;
  return std::stod(match[1].str());
}

// The shortest reply timeout of the study's controller links (s), nullopt without one.
std::optional<double> reply_timeout(const runtime::RunHeader& header) {
  const config::Deployment& deployment = header.study().deployment();
  std::optional<double> shortest;
  for (const config::NodeSpec& node : deployment.nodes())
    if (node.kind() == config::NodeSpec::CONTROLLER) {
      const double s = runtime::controller_reply_timeout(
          node.controller(), runtime::answer_window(deployment, header.dt()));
      shortest = shortest ? std::min(*shortest, s) : s;
    }
  return shortest;
}

}  // namespace

std::optional<double> stall_window(const std::string& status, const runtime::RunHeader& header) {
  static const std::regex missed("no answer for ([0-9]+) consecutive steps");
  static const std::regex answer_window("beyond its answer window of [0-9]+ steps \\(([0-9.]+) ms");
  static const std::regex watchdog("command watchdog: .*\\(limit ([0-9.]+) ms\\)");
  static const std::regex unanswered(
      "did not answer frame [0-9]+ \\(step [0-9]+\\) within ([0-9.]+) ms");
  if (auto steps = number_after(status, missed)) return *steps * header.dt();
  if (auto ms = number_after(status, answer_window)) return *ms * 1e-3;
  if (auto ms = number_after(status, watchdog)) return *ms * 1e-3;
  if (auto ms = number_after(status, unanswered)) return *ms * 1e-3;
  if (status.find("controller link was not clean") != std::string::npos &&
      status.find(", 0 rejected") != std::string::npos)
    return reply_timeout(header);
  return std::nullopt;
}

bool machine_can_pace(const MeasuredPlatform& machine, double dt) {
  return !(dt > 0.0) || machine.p99 < 0.5 * dt;
}

std::optional<std::string> machine_cannot_pace(const std::string& status,
                                               const runtime::RunHeader& header,
                                               const MeasuredPlatform& machine) {
  if (status.rfind("completed with deadline misses", 0) != 0 ||
      machine_can_pace(machine, header.dt()))
    return std::nullopt;
  char figures[128];
  std::snprintf(figures, sizeof figures,
                "its p99 wake-up lateness %.2f ms is at least half the %.2f ms step",
                machine.p99 * 1e3, header.dt() * 1e3);
  return "this machine could not pace the loop during the run (" + machine.text + "; " + figures +
         "), which failed the real-time verdict rightly: " + status;
}

std::optional<std::string> machine_loaded(const std::string& status,
                                          const runtime::RunHeader& header,
                                          const MeasuredPlatform& machine) {
  // The timing verdicts: the deadline's, a window's, and too few fresh answers (a node's answers
  // that came after the steps that needed them: coordinator/answer_verdict.cpp).
  const bool too_few_answers =
      status.rfind("failed: node ", 0) == 0 && status.find(" % needed)") != std::string::npos;
  const bool timing = status.rfind("completed with deadline misses", 0) == 0 ||
                      stall_window(status, header).has_value() || too_few_answers;
  if (!timing || machine.cpu_share >= kLoadedCpuShare) return std::nullopt;
  char figures[128];
  std::snprintf(figures, sizeof figures,
                "a busy thread got %.2f of its CPU, under the %.2f that marks a loaded machine",
                machine.cpu_share, kLoadedCpuShare);
  return "this machine was loaded around the run (" + machine.text + "; " + figures +
         "), which failed the run's timing rightly: " + status;
}

std::optional<std::string> machine_stalled(const std::string& status,
                                           const runtime::RunHeader& header,
                                           const MeasuredPlatform& machine) {
  if (auto why = machine_cannot_pace(status, header, machine)) return why;
  if (auto why = machine_loaded(status, header, machine)) return why;
  const std::optional<double> window = stall_window(status, header);
  if (!window) return std::nullopt;
  if (machine.max < 0.5 * *window) {
    // No one stall that long, but a machine that cannot pace the loop: the lateness of several
    // processes' wake-ups in a row (controller, node, coordinator) adds up past the window.
    if (machine_can_pace(machine, header.dt())) return std::nullopt;
    char pace[160];
    std::snprintf(pace, sizeof pace,
                  "its p99 wake-up lateness %.2f ms is at least half the %.2f ms step, and "
                  "the lateness of successive wake-ups adds up past the %.1f ms window",
                  machine.p99 * 1e3, header.dt() * 1e3, *window * 1e3);
    return "this machine could not pace the loop during the run (" + machine.text + "; " + pace +
           "), which failed the run rightly: " + status;
  }
  char figures[96];
  std::snprintf(figures, sizeof figures, "half the %.1f ms window that passed", *window * 1e3);
  return "this machine stalled during the run (" + machine.text + ") for at least " + figures +
         ", which failed the run rightly: " + status;
}

std::optional<double> loop_cpu_median(const std::string& coordinator_log) {
  static const std::regex line("loop CPU per step: median ([0-9.eE+-]+) ms");
  if (auto ms = number_after(coordinator_log, line)) return *ms * 1e-3;
  return std::nullopt;
}

std::optional<std::string> loop_cpu_over_bound(const std::string& coordinator_log) {
  const std::optional<double> median = loop_cpu_median(coordinator_log);
  if (!median) {
    if (coordinator_log.find("status: completed") == std::string::npos) return std::nullopt;
    return "the coordinator's summary of a completed run names no loop CPU per step:\n" +
           coordinator_log;
  }
  if (*median <= kLoopCpuMedianBound) return std::nullopt;
  char figures[160];
  std::snprintf(figures, sizeof figures,
                "the coordinator's loop burned a median %.3f ms of CPU per step, over the "
                "%.3f ms bound (a figure the machine's load does not move)",
                *median * 1e3, kLoopCpuMedianBound * 1e3);
  return figures;
}

WitnessedRun launch_witnessed(const std::string& name, const std::string& text,
                              const std::string& case_name, int domain, double timeout) {
  StallWitness witness;
  WitnessedRun out;
  out.run = launch(name, text, case_name, domain, timeout);
  out.machine = witness.finish();
  return out;
}

RealTimeVerdict real_time_verdict(const WitnessedRun& witnessed) {
  const LaunchedRun& run = witnessed.run;
  const std::string log = read_file(run.launch.coordinator_log);
  if (auto why = loop_cpu_over_bound(log)) return {RealTimeVerdict::kFailed, *why + "\n" + log};
  const runtime::RunFooter* footer = run.record.footer();
  if (run.launch.coordinator_exit == 0 && footer != nullptr && footer->ok())
    return {RealTimeVerdict::kCompleted, ""};
  const std::string status = footer != nullptr ? footer->status() : "no footer in the record";
  if (run.record.header() != nullptr)
    if (auto why = machine_stalled(status, *run.record.header(), witnessed.machine))
      return {RealTimeVerdict::kMachineStalled, *why};
  return {RealTimeVerdict::kFailed,
          "coordinator exit " + std::to_string(run.launch.coordinator_exit) + ": " + status +
              "\nthe machine meanwhile: " + witnessed.machine.text + "\n" + log};
}

}  // namespace rths::test
