#pragma once
// What the figures and the run summary call each actuator, and in which order they list them.
//
// Name: the site of the deployment node that hosts the actuator's channel (NodeSpec.site; a node
// with empty `storeys` hosts every experimental channel of its kind), with the channel beside it
// when that site hosts more than one ("lab_b, DOF 1"); without a site, the channel ("DOF 1",
// "storey 2", "element 1 (DOF 2 - DOF 1)").
// Order: the order the config declares them (substructuring.experimental_dofs or
// experimental_storeys as listed; every storey in turn for experimental_fraction), which is
// not always the channel order actuator indices follow (grounded DOFs, then elements).

#include <string>
#include <vector>

#include "core/substructure.h"
#include "rths/proto/config.pb.h"

namespace rths::analysis {

struct ActuatorNames {
  std::vector<std::string> names;  // per actuator index (channel order)
  std::vector<int> order;          // actuator indices, in config order
  // The name of actuator `a`; "actuator a+1" past the known ones.
  std::string of(int a) const;
};

ActuatorNames actuator_names(const config::Study& study, const core::HybridPartition& partition);

}  // namespace rths::analysis
