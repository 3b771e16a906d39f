#pragma once
// The meaning of a run record whose checksums hold (runtime/record/record.h checks the bytes; a
// record can be intact and still nonsense: crafted, or written by a broken program).
//
// check_record(contents) -> RecordChecks, every problem named with the entry number it was found
// in (0-based, the order read_record returns; "entry 57 (step 12): ..."):
//   header     missing; schema_version not kSchemaVersion; dofs outside [1, kMaxRecordDofs] or
//              actuators outside [0, dofs]: `fatal` (no table should be sized from it)
//   steps      each step number greater than the one before (no duplicate, no reversal); step 0
//              first; displacement, velocity and acceleration sized dofs (or empty), command,
//              realised and measured_force sized actuators (or empty); every value finite
//   ending     no footer while the record did not end inside an entry: the record was cut between
//              two entries (`cut`), which a reader reports as it reports a truncation
// Loading only; allocates; never throws for what it reads.

#include <string>
#include <vector>

#include "runtime/record/record.h"

namespace rths::runtime {

inline constexpr int kMaxRecordDofs = 10000;

struct RecordChecks {
  std::vector<std::string> problems;  // in entry order, header first
  bool fatal = false;  // the header cannot size a table: nothing may be built from the record
  bool cut = false;    // no footer and no truncation: the record stops between two entries
  bool ok() const { return problems.empty() && !cut; }
  // "N problems: <first>; <second>; ..." (at most `shown` listed, then "and M more").
  std::string summary(std::size_t shown = 10) const;
};

RecordChecks check_record(const RecordContents& contents);

}  // namespace rths::runtime
