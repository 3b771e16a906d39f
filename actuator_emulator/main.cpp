// rths-actuator-emulator: delay stages + actuator + emulated specimen behind DDS.
// See runtime/node/node_main.h.
#include "actuator_emulator/actuator_service.h"
#include "runtime/node/node_main.h"

int main(int argc, char** argv) {
  return rths::runtime::node_main(
      argc, argv, "rths-actuator-emulator", [](std::int32_t id, const std::string& run_id) {
        return std::make_unique<rths::actuator_emulator::ActuatorService>(id, run_id);
      });
}
