// rths-substructure-node: hosts numerical storeys behind DDS. See runtime/node/node_main.h.
#include "runtime/node/node_main.h"
#include "substructure_nodes/substructure_service.h"

int main(int argc, char** argv) {
  return rths::runtime::node_main(
      argc, argv, "rths-substructure-node", [](std::int32_t id, const std::string& run_id) {
        return std::make_unique<rths::substructure_nodes::SubstructureService>(id, run_id);
      });
}
