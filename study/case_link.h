#pragma once
// A case's network links (config CaseLink) as the in-process link model (core/link_answers.h).
// Units as the config: s, probability, s per s, steps.

#include <string>

#include "core/simulation.h"
#include "rths/proto/config.pb.h"

namespace rths::core {

// One way of a link, field for field.
LinkWay link_way(const config::LinkLag& lag);

// setup.links from a case's `link` blocks: none; one for every actuator; or one per actuator.
// Throws std::invalid_argument naming `where` and both counts otherwise.
void apply_case_links(HybridSetup& setup,
                      const google::protobuf::RepeatedPtrField<config::CaseLink>& links,
                      const std::string& where);

}  // namespace rths::core
