#pragma once
// The whole of a node program (substructure node, actuator emulator): parse the command line,
// open the DDS endpoint, run the node loop. Returns the process exit code:
// 0 stopped by the coordinator, 1 lost the coordinator / never assigned, 2 bad usage, 3 DDS error.
//
//   <program> --node-id N [--domain D | --config STUDY] --run-id ID [--assign-timeout S]
//             (STUDY is checked at start as `rths run` checks it, study::load_study, prepare_study
//             and check_deployment: a bad one is exit 2 with the message `run` gives)
//             (the run id may come from the config's deployment.run_id instead; none: exit 2)
//             [--security DIR/node_N]   (DDS Security; bad documents: exit 2 before DDS starts)
//             [--secret-file FILE | --insecure]  (the run secret, security/run_secret.h; none
//             and neither DDS Security nor --insecure: exit 2 before DDS starts)

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>

#include "runtime/node/node_service.h"

namespace rths::runtime {

using ServiceFactory =
    std::function<std::unique_ptr<NodeService>(std::int32_t node_id, const std::string& run_id)>;

int node_main(int argc, char** argv, const std::string& program, const ServiceFactory& factory);

// A number flag in [min, max], finite, for every program's flags: CLI::Range (and
// NonNegativeNumber) let "nan" through, as every comparison with NaN is false; this refuses it at
// parse time, "--rate: 'nan' is not a finite number", exit 2.
CLI::Validator finite_in(double min, double max);

}  // namespace rths::runtime
