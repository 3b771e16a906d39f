#pragma once
// One real-time run through a CONTROLLER node with the controller emulator on a host of its own:
// two network namespaces (deploy::NamespaceTopology, sites "host" and "rig"), the coordinator and
// the controller node in "host" (DDS on that namespace's loopback), rths-controller-emulator in
// "rig" with its plant paced at plant_hz, the controller link's UDP frames across the veth link.
// The emulator injects the link's lag itself (--answer-lag-ms: each answer leaves that long after
// its frame arrived); there is no kernel netem. Optionally the emulator is killed (SIGKILL) or
// silenced (SIGSTOP, SIGCONT after the run) once the record holds fault_step steps.
// Shared by bench/controller_rt (20 trials, figures) and tests/controller_node (a few, verdicts).
//
// Measured per run (wall clock = CLOCK_REALTIME, the stamps the record and logs carry):
//   controller_round_trip  the record's LinkSample.controller_round_trip of node 2, one sample per
//                          fresh answer (s): the frame's round trip as the node timed it, so its
//                          median minus answer_lag_ms is what the link and the emulator add.
//   round_trip             the record's DDS round trip of node 2 (s), the same samples.
//   hold_ms                fault -> the first HOLD: the node's own ("holding on its own", its log's
//                          realtime_ns) or the coordinator's ("HOLD sent" event in the record).
//   window_ms              the deployment's answer window in whole steps (ceil(ms / dt) x dt).
//   hold_frame_sent        the node's log says it sent HOLD frames (status 1) to the controller.
//   hold_frame_received    the emulator's log says it received a status HOLD frame (a killed
//                          emulator receives nothing: false).
//   plant_periods, plant_overruns  the emulator's own count at its exit (paced loop).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/node/lag.h"

namespace rths::test {

enum class ControllerFault { kNone, kKill, kStop };
std::string to_string(ControllerFault fault);

struct ControllerTrialSpec {
  ControllerFault fault = ControllerFault::kNone;
  long fault_step = 400;           // the fault comes once the record holds this many steps
  double rate_hz = 1024;           // the coordinator's (integrator's) rate
  double plant_hz = 4096;          // the emulator's plant: study.servo.rate
  double seconds = 2.0;            // of motion
  double answer_lag_ms = 0.3;      // injected by the emulator on each answer
  double answer_window_ms = 10.0;  // deployment.answer_window_ms (the node's lost window too)
  int domain = 184;                // DDS domain id, one per concurrent trial
  int node_port = 47160, peer_port = 47161;  // UDP: the node's and the emulator's
  std::string subnet = "10.231.40";          // the two sites' /24
  std::string deployment_extra;              // appended inside deployment { }
  std::filesystem::path dir;                 // scratch folder (created, emptied)
  std::filesystem::path binary_dir;          // the build tree (programs under its subfolders)
  std::string motion_path;                   // AT2 file
};

struct ControllerTrialResult {
  bool fault_delivered = false;  // false: the run ended (or failed) before the fault step
  std::string why_not;           // when a fault was asked for and not delivered
  int coordinator_exit = -1;
  int emulator_exit = -1;  // 128 + signal when a signal ended it
  std::string status;      // the record footer's
  long record_steps = 0;
  runtime::LagSummary controller_round_trip, round_trip;  // s
  double hold_ms = -1;                                    // < 0: no HOLD seen
  double window_ms = 0;
  bool hold_frame_sent = false, hold_frame_received = false;
  std::uint64_t plant_periods = 0, plant_overruns = 0;
};

// Throws NamespacesUnavailable (deploy/netns.h) where namespaces cannot be made,
// std::runtime_error when a program cannot be started.
ControllerTrialResult run_controller_trial(const ControllerTrialSpec& spec);

}  // namespace rths::test
