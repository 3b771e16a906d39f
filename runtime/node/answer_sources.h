#pragma once
// Which node of a run answers for which of its sources, as the coordinator plans the run: for
// readers of a record (`rths identify`'s replay of the answers the loop used) that need the
// deployment's assignment but not the rest of the plan.
//
// Input: the run's study (as the record header holds it), its step dt (s) and the folder its
// relative paths are relative to. The deployment is planned by plan_deployment (plan.h), the one
// planning the coordinator runs: the study's nodes, or its default nodes when it declares none.
// Output, per node in the deployment's order: its id, whether it is a substructure node, and the
// sources it answers for: the numerical storeys it hosts (0-based, ascending) for a substructure
// node, the actuators (indices into the partition's actuator storeys) for an actuator emulator or
// a controller. Throws std::invalid_argument as make_plan does (naming the node and the field).

#include <filesystem>
#include <vector>

#include "rths/proto/config.pb.h"

namespace rths::runtime {

struct NodeSources {
  int node_id = 0;
  bool numerical = false;    // a substructure node: `sources` are numerical storeys
  std::vector<int> sources;  // numerical storeys or actuators, 0-based
};

std::vector<NodeSources> answer_sources(const config::Study& study, double dt,
                                        const std::filesystem::path& base_dir);

}  // namespace rths::runtime
