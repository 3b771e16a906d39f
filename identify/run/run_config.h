#pragma once
// A distributed run's identified links and actuators written back as a study that `rths run` and
// `rths launch` accept, so a planned test can be run against the network and the actuators the
// record shows (`rths identify RECORD.rthsrec --out DIR`).
//
// The study is the run's own config (the record header's) with:
//   case "identified_actuator"  actuator 1's identified model as delay stages (study_config.h
//                               actuator_case of sensors.h rig_models; the declared stages where
//                               the record contradicted nothing of the actuator), behind the run
//                               case's compensation; it holds what the emulators' receive_delay
//                               stages did, which are cleared. A
//                               record of several actuators whose models differ: one case each,
//                               "identified_actuator_<a>" (a study case applies to every actuator).
//   per substructure link       receive_lag and send_lag from the measured round trip r (s), as a
//                               fitted distribution split evenly over both ways: one_way_delay =
//                               mean(r) / 2, jitter = std(r) / sqrt 2, loss = 1 - sqrt(1 - l) with
//                               l the lost share of the answers (wall clock, real-time runs);
//                               and the measured round trip as a trace file lag_node_<id>.csv
//                               (time s, delay s). In a real-time record, a substructure link's
//                               lag reached the response: its trace becomes the node's
//                               receive_delay trace stage, which replays it in simulated time too
//                               An emulator link keeps its declared lags: what its lag did to
//                               the response is in the actuator's fitted delay. Every link's
//                               trace is written, for plots and other studies.
// Relative paths of the header's study (motion, traces) are made absolute against `base_dir`
// (where the run was started from). Files: identified_run.textproto and the traces.

#include <filesystem>
#include <string>
#include <vector>

#include "identify/run/run_record.h"
#include "rths/proto/config.pb.h"

namespace rths::identify {

struct IdentifiedRun {
  config::Study study;
  std::vector<std::string> notes;  // what the study leaves out, per link or actuator
};

// The study above; the trace stages point to `trace_dir`/lag_node_<id>.csv. Throws
// std::invalid_argument when the run's study already has a case of the identified name.
IdentifiedRun identified_run(const RunIdentification& run, const std::filesystem::path& base_dir,
                             const std::filesystem::path& trace_dir);

// Writes identified_run.textproto and the traces into `dir`; returns "what: path" per file.
// Throws std::runtime_error naming a file that cannot be written.
std::vector<std::string> write_identified_run(const RunIdentification& run,
                                              const std::filesystem::path& base_dir,
                                              const std::filesystem::path& dir);

}  // namespace rths::identify
