#pragma once
// Test support (not part of any product library, so the coordinator does not link the node
// libraries). A distributed configuration run in one process: the same coordinator and the same node services
// (substructure node, actuator emulator), connected by transport::InProcessTransport instead of
// DDS. Deterministic; the reference a lockstep DDS run must equal bit for bit. Wall-clock lag
// injection does not apply (there is no wire).

#include "coordinator/coordinator.h"

namespace rths::coordinator {

RunOutcome run_in_process(const study::PreparedStudy& prepared, CoordinatorOptions options);

}  // namespace rths::coordinator
