#pragma once
// Envelope validation: a message is applied only if it belongs to this run, carries a known kind
// and parses, and its step is newer than the last one accepted from the same stream.
//
//   run id differs                      -> kForeignRun
//   kind unknown or payload unparsable  -> kGarbage
//   step == last accepted               -> kDuplicate
//   step <  last accepted               -> kStale
//   step beyond what was ever commanded -> kOutOfOrder (a reply to a command never sent)
//   node id not the one whose topic carried it, or another writer than the one pinned for that
//   node, or a control message (ASSIGN, COMMAND, HOLD, STOP) on the broadcast topic
//                                       -> kNotEntitled
//   a decoded value not finite or beyond the run's limits -> kOutOfRange
// Every rejection is counted; nothing rejected is applied.

#include <cmath>
#include <cstdint>
#include <string>

#include "rths/proto/runtime.pb.h"
#include "transport/transport.h"

namespace rths::runtime {

enum class Verdict {
  kAccept,
  kForeignRun,
  kGarbage,
  kDuplicate,
  kStale,
  kOutOfOrder,
  kUnknownNode,
  kNotEntitled,
  kOutOfRange
};

std::string to_string(Verdict verdict);

// Run id and kind only (before parsing the payload). An empty run id is never this run's.
Verdict check_envelope(const transport::Message& message, const std::string& run_id);

// Whether the sender may speak as message.node_id: the topic that carried it is that node's
// (topic_node), and, once a writer is pinned for it (`pinned` != 0), it came from that writer
// (a transport without writer identities stamps 0, which is not checked).
Verdict check_sender(const transport::Message& message, std::uint64_t pinned);

// Whether every value is finite and |value| <= limit (limit <= 0: finite only).
template <class Values>
bool finite_within(const Values& values, double limit) {
  for (const double x : values)
    if (!std::isfinite(x) || (limit > 0 && std::abs(x) > limit)) return false;
  return true;
}

// Step ordering for one stream: `last_accepted` (-1 before any), `newest_possible` the largest
// step the peer may legitimately send (the last commanded step; INT64_MAX for commands).
Verdict check_step(std::int64_t step, std::int64_t last_accepted, std::int64_t newest_possible);

class RejectCounters {
 public:
  void count(Verdict verdict);
  void add(const RejectCounters& other);
  std::uint64_t total() const;
  void fill(Counters& counters) const;
  // Counters' reject fields only, back (for a node's report in its heartbeat).
  static RejectCounters from(const Counters& counters);
  std::uint64_t foreign_run = 0, garbage = 0, duplicate = 0, stale = 0, out_of_order = 0,
                unknown_node = 0, not_entitled = 0, out_of_range = 0;
};

}  // namespace rths::runtime
