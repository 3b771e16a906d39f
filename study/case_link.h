#pragma once
// A case's network links (config CaseLink) as the in-process link model (core/link_answers.h).
// Units as the config: s, probability, s per s, steps.

#include <string>

#include "core/simulation.h"
#include "rths/proto/config.pb.h"

namespace rths::study {

// One way of a link, field for field.
core::LinkWay link_way(const config::LinkLag& lag);

// setup.links from a case's `link` blocks: none; one for every actuator; or one per actuator.
// Throws std::invalid_argument naming `where` and both counts otherwise.
void apply_case_links(core::HybridSetup& setup,
                      const google::protobuf::RepeatedPtrField<config::CaseLink>& links,
                      const std::string& where);

// The largest lag an actuator's answer carries (s): its chain's nominal delay (negative: a lead)
// and its link's round trip (core::nominal_round_trip), over the actuators; what a case's
// critical-delay check weighs.
double answer_lag(const core::HybridSetup& setup);

// What a case's delay column says: the first actuator's chain, and its link when it has one
// ("shift(14 ms); link 30 ms, jitter 2.5 ms, loss 1 %, drift 0.1 ms/s each way").
std::string case_delay_text(const core::HybridSetup& setup);

}  // namespace rths::study
