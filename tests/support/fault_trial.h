#pragma once
// One fault trial of a real-time distributed run (coordinator, substructure node, actuator
// emulator as real processes over Cyclone DDS on loopback): at a chosen step, SIGKILL or SIGSTOP
// one process, then measure what the fail-safe did. Shared by bench/fault_trials (N random
// trials, figures) and the test suite (a few fixed trials, assertions).
//
// Measured per trial (wall clock = CLOCK_REALTIME, the stamps the record and logs carry):
//   steps_after_fault   record steps whose work began after the fault (the coordinator integrated
//                       them on an old answer); 0 when the coordinator is the victim. Counted
//                       from the fault's stamp, so a stall between the stamp and the signal's
//                       delivery adds the steps the victim still answered.
//   steps_unanswered    record steps after the last one at which the victim's answered step
//                       advanced: what the coordinator's answer window bounds (its contract,
//                       free of when the signal landed); 0 when the coordinator is the victim.
//   hold_ms             fault -> the emulator's HOLD (its log line's realtime_ns), whoever caused
//                       it; < 0 when the emulator is the victim or never logged a HOLD.
//   stop_ms             fault -> the coordinator's "HOLD sent" event in the record; < 0 when the
//                       coordinator is the victim.
//   record_complete     the record reads, its steps are 0..n without a gap, and every step whose
//                       work began before the fault is present (a surviving coordinator's record
//                       goes on past the fault) except, for a killed coordinator, the ones its
//                       writer had not yet written (bounded by the queue).
//   names_node          the coordinator's log names the victim (coordinator victim: the
//                       emulator's log says "command watchdog").

#include <filesystem>
#include <string>
#include <vector>

namespace rths::test {

enum class FaultVictim { kCoordinator, kSubstructure, kEmulator };
std::string to_string(FaultVictim victim);

struct FaultTrialSpec {
  FaultVictim victim = FaultVictim::kSubstructure;
  int signal = 9;                // SIGKILL or SIGSTOP
  long fault_step = 500;         // the fault comes once the record holds this many steps
  double rate_hz = 1024;         // integrator rate
  double seconds = 3.0;          // of the record
  int domain = 60;               // DDS domain id, one per concurrent trial
  std::string deployment_extra;  // appended inside deployment { } (e.g. max_missed_answers: 30)
  // Appended to the coordinator's arguments; default: no platform measurement (recorded so).
  std::vector<std::string> coordinator_extra{"--platform-seconds", "0", "--accept-platform"};
  std::filesystem::path dir;         // scratch folder (created, emptied)
  std::filesystem::path binary_dir;  // the build tree (programs under its subfolders)
  std::string motion_path;           // AT2 file
};

struct FaultTrialResult {
  bool fault_delivered = false;  // false: the run ended (or failed) before the fault step
  std::string why_not;           // when !fault_delivered
  long steps_after_fault = 0;
  long steps_unanswered = 0;
  double hold_ms = -1, stop_ms = -1;
  bool record_complete = false;
  bool names_node = false;
  int coordinator_exit = -1;  // -1: the coordinator was the victim
  long record_steps = 0;      // also when the fault was not delivered: steps run healthy
};

// Throws std::runtime_error when a program cannot be started.
FaultTrialResult run_fault_trial(const FaultTrialSpec& spec);

}  // namespace rths::test
