#include "tests/support/in_process_run.h"

#include "actuator_emulator/actuator_service.h"
#include "substructure_nodes/substructure_service.h"
#include "transport/in_process.h"

namespace rths::coordinator {

RunOutcome run_in_process(const study::PreparedStudy& prepared, CoordinatorOptions options) {
  transport::InProcessTransport transport;
  Coordinator coordinator(prepared, transport, options);
  std::vector<std::unique_ptr<runtime::NodeService>> services;
  for (const runtime::NodePlan& node : coordinator.plan().nodes) {
    if (node.spec.kind() == config::NodeSpec::SUBSTRUCTURE)
      services.push_back(std::make_unique<substructure_nodes::SubstructureService>(node.spec.id(),
                                                                                   options.run_id));
    else
      services.push_back(
          std::make_unique<actuator_emulator::ActuatorService>(node.spec.id(), options.run_id));
    transport.attach(node.spec.id(), *services.back());
  }
  return coordinator.run();
}

}  // namespace rths::coordinator
