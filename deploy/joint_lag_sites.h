#pragma once
// The across-sites part of the joint network x actuator lag study (analysis/joint_lag/joint_lag.h): selected
// points run across network-namespace sites (deploy/sites.h) with the clock of the study's sites
// config, the network round trip R injected half each way on the actuator emulator's link (delay
// only: no jitter, no loss), the actuator lag A as the case's delay stage, `measured_duration` s
// of the motion (5 s when 0). From each run's record (runtime::measure_run):
//   real time  the coordinator uses the newest feedback it has, so the realised displacement it
//              records lags the command by round trip + actuator lag: total = J1(command,
//              realised); network = round-trip median; actuator = their difference.
//   lockstep   each command is paired with its own answer: actuator = J1, network = round-trip
//              median, total = their sum. (The result itself sees only the actuator lag.)
// Error against the in-process reference over the same duration. Each run writes its outputs to
// <output directory>/measured_R<ms>ms_A<ms>ms.

#include "analysis/joint_lag/joint_lag.h"

namespace rths::deploy {

// unavailable: deploy::namespace_support(); run: the runs above. Pass it as
// analysis::JointLagOptions::across_sites.
analysis::JointLagAcrossSites joint_lag_across_sites();

}  // namespace rths::deploy
