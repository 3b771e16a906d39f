#pragma once
// One reading of each node's health at the end of a run, from its footer entry (NodeRejects):
// the controller link's frames and the age of the answers the coordinator applied. The
// coordinator's summary, `rths launch`'s summary and summary.json, and `rths export` all print it
// through these, so they cannot disagree.
//   controller_link_text(n)   "" for a node without a controller link; else one line: frames
//                             sent, accepted, late, lost, rejected by cause ("rejected: none"
//                             only when every cause is 0), the UDP round trip (median, p99, max,
//                             ms, the node's clock) and the hold (HOLD frames, held after ms).
//   answer_age_text(n)        "" when no step was judged (lockstep); else the applied answers'
//                             age, median, p99 and max in steps and ms, against the window.
//   node_health_json(n)       both as JSON: {"controller": {...} | null, "answer_age": {...} |
//   null} link_verdict(n)           why the run cannot pass as clean: frames lost, late, or
//   rejected
//                             (any cause: a second sender, a damaged frame), named with counts;
//                             nullopt when the link was clean (or the node has none).

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "rths/proto/runtime.pb.h"

namespace rths::runtime {

std::uint64_t controller_rejected(const ControllerReport& r);
std::string controller_link_text(const NodeRejects& node);
std::string answer_age_text(const NodeRejects& node);
nlohmann::json node_health_json(const NodeRejects& node);
std::optional<std::string> link_verdict(const NodeRejects& node);

}  // namespace rths::runtime
