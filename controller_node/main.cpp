// rths-controller-node: a lab's real-time controller over UDP frames behind DDS.
// See controller_node/controller_service.h and runtime/node/node_main.h.
#include "controller_node/controller_service.h"
#include "runtime/node/node_main.h"

int main(int argc, char** argv) {
  return rths::runtime::node_main(
      argc, argv, "rths-controller-node", [](std::int32_t id, const std::string& run_id) {
        return std::make_unique<rths::controller_node::ControllerService>(id, run_id);
      });
}
