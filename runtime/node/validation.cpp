#include "runtime/node/validation.h"

namespace rths::runtime {

std::string to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::kAccept: return "accept";
    case Verdict::kForeignRun: return "foreign run";
    case Verdict::kGarbage: return "garbage";
    case Verdict::kDuplicate: return "duplicate";
    case Verdict::kStale: return "stale";
    case Verdict::kOutOfOrder: return "out of order";
    case Verdict::kUnknownNode: return "unknown node";
    case Verdict::kNotEntitled: return "not entitled";
    case Verdict::kOutOfRange: return "out of range";
  }
  return "?";
}

Verdict check_envelope(const transport::Message& message, const std::string& run_id) {
  if (message.run_id.empty() || message.run_id != run_id) return Verdict::kForeignRun;
  if (!MessageKind_IsValid(message.kind) || message.kind == MESSAGE_KIND_UNSPECIFIED)
    return Verdict::kGarbage;
  return Verdict::kAccept;
}

Verdict check_sender(const transport::Message& message, std::uint64_t pinned) {
  if (message.topic_node != message.node_id) return Verdict::kNotEntitled;
  if (pinned != 0 && message.writer != 0 && message.writer != pinned) return Verdict::kNotEntitled;
  return Verdict::kAccept;
}

Verdict check_step(std::int64_t step, std::int64_t last_accepted, std::int64_t newest_possible) {
  if (step == last_accepted) return Verdict::kDuplicate;
  if (step < last_accepted) return Verdict::kStale;
  if (step > newest_possible) return Verdict::kOutOfOrder;
  return Verdict::kAccept;
}

void RejectCounters::count(Verdict verdict) {
  switch (verdict) {
    case Verdict::kAccept: break;
    case Verdict::kForeignRun: ++foreign_run; break;
    case Verdict::kGarbage: ++garbage; break;
    case Verdict::kDuplicate: ++duplicate; break;
    case Verdict::kStale: ++stale; break;
    case Verdict::kOutOfOrder: ++out_of_order; break;
    case Verdict::kUnknownNode: ++unknown_node; break;
    case Verdict::kNotEntitled: ++not_entitled; break;
    case Verdict::kOutOfRange: ++out_of_range; break;
  }
}

void RejectCounters::add(const RejectCounters& o) {
  foreign_run += o.foreign_run;
  garbage += o.garbage;
  duplicate += o.duplicate;
  stale += o.stale;
  out_of_order += o.out_of_order;
  unknown_node += o.unknown_node;
  not_entitled += o.not_entitled;
  out_of_range += o.out_of_range;
}

std::uint64_t RejectCounters::total() const {
  return foreign_run + garbage + duplicate + stale + out_of_order + unknown_node + not_entitled +
         out_of_range;
}

void RejectCounters::fill(Counters& c) const {
  c.set_foreign_run(foreign_run);
  c.set_garbage(garbage);
  c.set_duplicate(duplicate);
  c.set_stale(stale);
  c.set_out_of_order(out_of_order);
  c.set_unknown_node(unknown_node);
  c.set_not_entitled(not_entitled);
  c.set_out_of_range(out_of_range);
}

RejectCounters RejectCounters::from(const Counters& c) {
  RejectCounters r;
  r.foreign_run = c.foreign_run();
  r.garbage = c.garbage();
  r.duplicate = c.duplicate();
  r.stale = c.stale();
  r.out_of_order = c.out_of_order();
  r.unknown_node = c.unknown_node();
  r.not_entitled = c.not_entitled();
  r.out_of_range = c.out_of_range();
  return r;
}

}  // namespace rths::runtime
