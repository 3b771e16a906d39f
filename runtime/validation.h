#pragma once
// Envelope validation: a message is applied only if it belongs to this run, carries a known kind
// and parses, and its step is newer than the last one accepted from the same stream.
//
//   run id differs                      -> kForeignRun
//   kind unknown or payload unparsable  -> kGarbage
//   step == last accepted               -> kDuplicate
//   step <  last accepted               -> kStale
//   step beyond what was ever commanded -> kOutOfOrder (a reply to a command never sent)
// Every rejection is counted; nothing rejected is applied.

#include <cstdint>
#include <string>

#include "rths/proto/runtime.pb.h"
#include "transport/transport.h"

namespace rths::runtime {

enum class Verdict { kAccept, kForeignRun, kGarbage, kDuplicate, kStale, kOutOfOrder, kUnknownNode };

std::string to_string(Verdict verdict);

// Run id and kind only (before parsing the payload).
Verdict check_envelope(const transport::Message& message, const std::string& run_id);

// Step ordering for one stream: `last_accepted` (-1 before any), `newest_possible` the largest
// step the peer may legitimately send (the last commanded step; INT64_MAX for commands).
Verdict check_step(std::int64_t step, std::int64_t last_accepted, std::int64_t newest_possible);

class RejectCounters {
 public:
  void count(Verdict verdict);
  void add(const RejectCounters& other);
  std::uint64_t total() const;
  void fill(Counters& counters) const;
  std::uint64_t foreign_run = 0, garbage = 0, duplicate = 0, stale = 0, out_of_order = 0,
                unknown_node = 0;
};

}  // namespace rths::runtime
