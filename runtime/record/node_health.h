#pragma once
// One reading of each node's health at the end of a run, from its footer entry (NodeRejects):
// the controller link's frames and the age of the answers the coordinator applied. The
// coordinator's summary, `rths launch`'s summary and summary.json, and `rths export` all print it
// through these, so they cannot disagree.
//   controller_link_text(n)  "" for a node without a controller link; else one line: frames
//                            sent, accepted, answered late, lost (no answer within the reply
//                            timeout: one meaning everywhere), UDP frames rejected by cause
//                            ("UDP frames rejected: none" only when every cause is 0: never to
//                            be read as the DDS rejects), the UDP round trip (median and p99 of
//                            the applied answers, max of every answer, late ones included; ms,
//                            the node's clock), the hold (HOLD frames, held after ms, answers
//                            that did not end it, a restart detected), lost and late frames
//                            located (frame and step, the first 8), ICMP errors with their
//                            errno, datagrams drained before connect.
//   answer_age_text(n)       "" when no step was judged (lockstep); else the applied answers'
//                            age, median, p99 and max in steps and ms, against the window.
//   node_health_json(n)      both as JSON: {"controller": {...} | null, "answer_age": {...} |
//                            null}; the controller's "hold" holds the hold table (every HOLD
//                            frame, answer and STOP: kind, time_s, frame, status, position_m,
//                            force_N, verdict), "lost_frames" and "late_frames" every located one.
//   link_verdict(n)          why the run cannot pass as clean: frames lost, late, or rejected
//                            (any cause: a second sender, a damaged frame), named with counts;
//                            nullopt when the link was clean (or the node has none).

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
