// The controller link in real time, across network namespaces (not a test; the test suite runs a
// few runs of the same harness, tests/controller_node/controller_rt_test.cpp). A 1024 Hz
// coordinator and its CONTROLLER node in one namespace, rths-controller-emulator with its plant
// paced at 4096 Hz in another, the UDP frames across a veth link, the link's lag injected by the
// emulator on each answer (tests/support/controller_trial.h). Prints:
//   one healthy run: the record's controller round trip (median, p99, max) against the injected
//     lag (target: median within 0.2 ms of it), the DDS round trip beside it, the emulator's plant
//     periods and overruns, the run's status;
//   runs with the emulator killed (SIGKILL) at a random step until --trials faults were delivered
//     (at most 3 x --trials runs), then as many with it silenced (SIGSTOP, SIGCONT after the run):
//     ms from the fault to the first HOLD (target: within the answer window in whole steps + 2 ms,
//     as bench/fault_trials judges an emulator's fail-safe), whether the node sent its HOLD status
//     frame and (silenced) the emulator received it; and the false stops: runs the fail-safe
//     stopped before the fault came (a stall of the machine longer than the window), which deliver
//     no fault and are not trials.
// Needs root (namespaces). Exit 0 when every target was met, 1 otherwise, 2 on bad usage.
//
//   rths_controller_rt_bench [--trials N] [--seconds S] [--lag-ms MS] [--window-ms MS]
//                            [--domain D] [--seed S] [--extra "deployment fields"]
#include <CLI/CLI.hpp>

#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#include "deploy/netns.h"
#include "tests/support/controller_trial.h"

namespace {

using namespace rths;

constexpr double kRoundTripTolerance = 0.2e-3;  // s, |median - injected lag|
constexpr double kHoldMargin = 2.0;             // ms past the window

struct Setting {
  int trials = 20, domain = 184, index = 0;
  unsigned seed = 1;
  double seconds = 4.0, trial_seconds = 2.0, lag_ms = 0.3, window_ms = 20.0;
  std::string extra;
};

test::ControllerTrialSpec spec_for(const Setting& s, test::ControllerFault fault, int index) {
  test::ControllerTrialSpec spec;
  spec.fault = fault;
  spec.seconds = fault == test::ControllerFault::kNone ? s.seconds : s.trial_seconds;
  spec.answer_lag_ms = s.lag_ms;
  spec.answer_window_ms = s.window_ms;
  spec.domain = s.domain;
  spec.node_port = 47160 + 2 * (index % 10);
  spec.peer_port = spec.node_port + 1;
  spec.deployment_extra = s.extra;
  spec.dir =
      std::filesystem::temp_directory_path() / ("rths_controller_rt_" + std::to_string(index));
  spec.binary_dir = RTHS_BINARY_DIR;
  spec.motion_path = std::string(RTHS_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
  return spec;
}

bool healthy_run(const Setting& s) {
  const test::ControllerTrialResult r =
      test::run_controller_trial(spec_for(s, test::ControllerFault::kNone, 0));
  const auto& c = r.controller_round_trip;
  const double off = c.median - s.lag_ms * 1e-3;
  const bool agrees = c.count > 0 && std::abs(off) <= kRoundTripTolerance;
  std::printf(
      "healthy run: %s, %ld steps, coordinator exit %d, emulator exit %d\n"
      "  controller round trip (%zu answers): median %.3f ms, p99 %.3f ms, max %.3f ms; injected "
      "%.3f ms; median - injected %.3f ms (target within %.1f ms: %s)\n"
      "  DDS round trip coordinator <-> node: median %.3f ms, p99 %.3f ms\n"
      "  emulator plant: %llu periods, %llu overruns\n",
      r.status.c_str(), r.record_steps, r.coordinator_exit, r.emulator_exit, c.count,
      c.median * 1e3, c.p99 * 1e3, c.max * 1e3, s.lag_ms, off * 1e3, kRoundTripTolerance * 1e3,
      agrees ? "yes" : "NO", r.round_trip.median * 1e3, r.round_trip.p99 * 1e3,
      static_cast<unsigned long long>(r.plant_periods),
      static_cast<unsigned long long>(r.plant_overruns));
  return agrees;
}

struct Tally {
  int run = 0, delivered = 0, held = 0, sent = 0, received = 0;
  std::vector<double> holds;
};

void fault_trial(Setting& s, test::ControllerFault fault, long step, Tally& t) {
  ++t.run;
  const int index = ++s.index;
  auto spec = spec_for(s, fault, index);
  spec.fault_step = step;
  const test::ControllerTrialResult r = test::run_controller_trial(spec);
  std::printf("trial %2d: %-7s at step %5ld: ", index, test::to_string(fault).c_str(), step);
  if (!r.fault_delivered) {
    std::printf("false stop before the fault: %s\n", r.status.substr(0, 200).c_str());
    return;
  }
  ++t.delivered;
  const bool in_window = r.hold_ms >= 0 && r.hold_ms <= r.window_ms + kHoldMargin;
  t.held += in_window;
  t.sent += r.hold_frame_sent;
  t.received += r.hold_frame_received;
  if (r.hold_ms >= 0) t.holds.push_back(r.hold_ms);
  std::printf("HOLD %7.2f ms (window %.2f ms) %s, HOLD frame %s%s, %s\n", r.hold_ms, r.window_ms,
              in_window ? "in time" : "LATE", r.hold_frame_sent ? "sent" : "NOT SENT",
              fault == test::ControllerFault::kStop
                  ? (r.hold_frame_received ? ", received after SIGCONT" : ", NOT RECEIVED")
                  : "",
              r.status.c_str());
}

bool print_tally(const char* what, const Tally& t, bool expect_received) {
  const auto hold = runtime::summarize(t.holds);
  std::printf(
      "%s: %d runs, %d faults delivered, %d false stops; HOLD within the window + %.0f ms: %d/%d "
      "(median %.2f ms, max %.2f ms); HOLD frame sent %d/%d",
      what, t.run, t.delivered, t.run - t.delivered, kHoldMargin, t.held, t.delivered, hold.median,
      hold.max, t.sent, t.delivered);
  if (expect_received) std::printf(", received by the emulator %d/%d", t.received, t.delivered);
  std::printf("\n");
  return t.delivered > 0 && t.held == t.delivered && t.sent == t.delivered &&
         (!expect_received || t.received == t.delivered);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"the controller link in real time across network namespaces: lag and fail-safe"};
  Setting s;
  app.add_option("--trials", s.trials, "faults delivered per kind, kill and stop (default 20)");
  app.add_option("--seconds", s.seconds, "s of motion of the healthy run (default 4)");
  app.add_option("--trial-seconds", s.trial_seconds, "s of motion of a fault trial (default 2)");
  app.add_option("--lag-ms", s.lag_ms, "lag the emulator adds to each answer (default 0.3)")
      ->check(CLI::Range(0.0, 0.9));
  app.add_option("--window-ms", s.window_ms, "answer window and command watchdog (default 20)");
  app.add_option("--domain", s.domain, "DDS domain id (default 184)");
  app.add_option("--seed", s.seed, "random seed of the fault steps (default 1)");
  app.add_option("--extra", s.extra, "extra deployment fields, e.g. \"min_answer_fraction: -1\"");
  CLI11_PARSE(app, argc, argv);
  if (const auto why = deploy::namespace_support()) {
    std::fprintf(stderr, "rths_controller_rt_bench: no network namespaces here: %s\n",
                 why->c_str());
    return 2;
  }
  bool ok = healthy_run(s);
  std::mt19937 random(s.seed);
  const long steps = static_cast<long>(s.trial_seconds * 1024);
  std::uniform_int_distribution<long> step_of(300, std::max<long>(301, steps - 400));
  Tally killed, silenced;
  for (auto [fault, tally] : {std::pair{test::ControllerFault::kKill, &killed},
                              std::pair{test::ControllerFault::kStop, &silenced}})
    while (tally->delivered < s.trials && tally->run < 3 * s.trials)
      fault_trial(s, fault, step_of(random), *tally);
  ok = print_tally("emulator killed (SIGKILL)", killed, false) && ok;
  ok = print_tally("emulator silenced (SIGSTOP)", silenced, true) && ok;
  return ok ? 0 : 1;
}
