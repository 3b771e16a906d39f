// Fault trials (not a test). Runs N real-time runs of the paper's frame at 1024 Hz with the
// deployment's default fail-safe (max_missed_answers 3, command watchdog 3 periods); in each, one
// random process (coordinator, substructure node, actuator emulator) gets SIGKILL or SIGSTOP at a
// random step. Prints per trial and in total:
//   steps the coordinator integrated after the fault (target <= max_missed_answers; how many
//   stayed within max_missed_answers - 1 is printed too),
//   ms from the fault to the emulator's HOLD (target <= 5 ms) and to the coordinator's stop,
//   whether the record is complete up to the fault, and whether the stop names the victim;
//   and the healthy runs the fail-safe stopped before the fault came (false trips), by cause.
// With --delivered N it keeps running trials until N faults were delivered (at most --trials).
//
//   fault_trials [--trials N] [--delivered N] [--seed S] [--domain D] [--rate HZ] [--extra "..."]
#include <CLI/CLI.hpp>

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <vector>

#include "runtime/lag.h"
#include "tests/support/fault_trial.h"

int main(int argc, char** argv) {
  using namespace rths;
  CLI::App app{"fault trials: kill or stall a node of a real-time run, measure the fail-safe"};
  int trials = 100, domain = 60, wanted = 0;
  unsigned seed = 1;
  double rate = 1024, seconds = 2.5;
  std::string extra;
  app.add_option("--trials", trials, "number of trials (default 100)");
  app.add_option("--delivered", wanted,
                 "run until this many faults were delivered (at most --trials trials; default: "
                 "run exactly --trials)");
  app.add_option("--seed", seed, "random seed (default 1)");
  app.add_option("--domain", domain, "first of 10 DDS domain ids (default 60)");
  app.add_option("--rate", rate, "integrator rate, Hz (default 1024)");
  app.add_option("--seconds", seconds, "s of record per run (default 2.5)");
  app.add_option("--extra", extra, "extra deployment fields, e.g. \"max_missed_answers: 5\"");
  CLI11_PARSE(app, argc, argv);

  std::mt19937 random(seed);
  const long steps = static_cast<long>(seconds * rate);
  std::uniform_int_distribution<long> step_of(200, std::max<long>(201, steps - 300));
  std::uniform_int_distribution<int> victim_of(0, 2), signal_of(0, 1);
  int delivered = 0, held_5ms = 0, hold_cases = 0, within_steps = 0, step_cases = 0, complete = 0,
      named = 0, exit_ok = 0, exit_cases = 0, within_missed = 0, run = 0, tripped_missed = 0,
      tripped_watchdog = 0, tripped_other = 0;
  std::vector<double> holds, stops, after;
  for (int i = 0; i < trials && (wanted <= 0 || delivered < wanted); ++i) {
    ++run;
    test::FaultTrialSpec spec;
    spec.victim = static_cast<test::FaultVictim>(victim_of(random));
    spec.signal = signal_of(random) == 0 ? SIGKILL : SIGSTOP;
    spec.fault_step = step_of(random);
    spec.rate_hz = rate;
    spec.seconds = seconds;
    spec.domain = domain + i % 10;
    spec.deployment_extra = extra;
    spec.dir = std::filesystem::temp_directory_path() / ("rths_fault_trial_" + std::to_string(i));
    spec.binary_dir = RTHS_BINARY_DIR;
    spec.motion_path =
        std::string(RTHS_SHARED_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
    const test::FaultTrialResult r = test::run_fault_trial(spec);
    std::printf("trial %3d: %-12s %-7s at step %5ld: ", i, test::to_string(spec.victim).c_str(),
                spec.signal == SIGKILL ? "SIGKILL" : "SIGSTOP", spec.fault_step);
    if (!r.fault_delivered) {
      std::printf("not delivered: %s\n", r.why_not.substr(0, 200).c_str());
      if (r.why_not.find("command watchdog") != std::string::npos) ++tripped_watchdog;
      else if (r.why_not.find("consecutive steps") != std::string::npos) ++tripped_missed;
      else ++tripped_other;
      continue;
    }
    ++delivered;
    std::printf("steps after %2ld, hold %7.2f ms, stop %7.2f ms, record %s (%ld steps), %s, exit %d\n",
                r.steps_after_fault, r.hold_ms, r.stop_ms, r.record_complete ? "complete" : "INCOMPLETE",
                r.record_steps, r.names_node ? "names it" : "DOES NOT NAME IT", r.coordinator_exit);
    if (spec.victim != test::FaultVictim::kEmulator) {
      ++hold_cases;
      if (r.hold_ms >= 0) holds.push_back(r.hold_ms);
      held_5ms += r.hold_ms >= 0 && r.hold_ms <= 5.0 ? 1 : 0;
    }
    if (spec.victim != test::FaultVictim::kCoordinator) {
      ++step_cases;
      after.push_back(static_cast<double>(r.steps_after_fault));
      within_steps += r.steps_after_fault <= 3 ? 1 : 0;   // max_missed_answers (3)
      within_missed += r.steps_after_fault <= 2 ? 1 : 0;  // and within one fewer
      if (r.stop_ms >= 0) stops.push_back(r.stop_ms);
      ++exit_cases;
      exit_ok += r.coordinator_exit == 1 ? 1 : 0;
    }
    complete += r.record_complete ? 1 : 0;
    named += r.names_node ? 1 : 0;
  }
  const auto hold = runtime::summarize(holds), stop = runtime::summarize(stops),
             steps_after = runtime::summarize(after);
  std::printf(
      "\n%d trials, %d faults delivered (rate %.0f Hz, %s)\n"
      "emulator HOLD within 5 ms of the fault: %d/%d (median %.2f ms, max %.2f ms)\n"
      "coordinator integrated <= 3 steps (max_missed_answers) past the fault: %d/%d, <= 2: %d/%d "
      "(median %.1f, max %.0f)\n"
      "coordinator stop after the fault: median %.2f ms, max %.2f ms; exit 1: %d/%d\n"
      "record complete up to the fault: %d/%d\n"
      "the stop names the victim: %d/%d\n"
      "healthy runs the fail-safe stopped before the fault: %d of %d (coordinator, missed answers: "
      "%d; emulator, command watchdog: %d; other: %d)\n",
      run, delivered, rate, extra.empty() ? "default fail-safe" : extra.c_str(), held_5ms,
      hold_cases, hold.median, hold.max, within_steps, step_cases, within_missed, step_cases,
      steps_after.median,
      steps_after.max, stop.median, stop.max, exit_ok, exit_cases, complete, delivered, named,
      delivered, run - delivered, run, tripped_missed, tripped_watchdog, tripped_other);
  return 0;
}
