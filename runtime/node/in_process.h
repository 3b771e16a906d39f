#pragma once
// The in-process run that a distributed run of the same case is compared with.
//
// in_process_setup  the case's setup (study::setup_for_case: its delay stages and compensation)
//                   with the compensation of each actuator emulator of the deployment (its default
//                   nodes when it declares none; runtime::with_node_compensation). core::simulate
//                   of it is what a lockstep distributed run without node delay stages equals bit
//                   for bit; the links' lag and the nodes' own delay stages are not in it.
// Throws std::invalid_argument as runtime::make_plan and with_node_compensation do (naming the
// node and the field).

#include "study/study.h"

namespace rths::runtime {

core::HybridSetup in_process_setup(const study::PreparedStudy& prepared,
                                   const config::Case& study_case);

}  // namespace rths::runtime
