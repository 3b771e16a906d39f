#pragma once
// The meaning of a run record whose checksums hold (runtime/record/record.h checks the bytes; a
// record can be intact and still nonsense: crafted, or written by a broken program).
//
// check_record(contents) -> RecordChecks, every problem named with the entries (0-based, the
// order read_record returns) and steps it was found in; the same problem in consecutive steps is
// one region ("entries 103-203 (steps 100-200, 101 steps): ..."), one in a single step reads
// "entry 57 (step 55): ...":
//   header     missing (read with the header the reader assumed from the steps, which is named);
//              schema_version not kSchemaVersion; dt not finite or not > 0; dofs outside
//              [1, kMaxRecordDofs] or actuators outside [0, dofs]: `fatal` (no table should be
//              sized from it); a header copy that differs from the first intact one (the field
//              paths that differ are named); an intact inputs entry whose payload CRC-32C is not
//              the header's inputs_crc32c (when it names one); no intact inputs entry while the
//              header names one and no damaged region lies before the first step (where it was)
//   steps      step 0 first; each step number greater than the one before (no duplicate, no
//              reversal) and, unless a damaged region lies between them, exactly one greater (a
//              gap no loss explains is named); time finite, never less than the step before's,
//              and within dt / 2 of step x dt; displacement, velocity and acceleration sized
//              dofs (or empty), command, realised and measured_force sized actuators (or empty);
//              every value finite and within its bound: the study's deployment limits when set
//              (|u| <= max_displacement, |v| <= max_velocity, |command|, |realised| <= twice
//              max_displacement: a drift spans two DOFs), else the plausible bounds below;
//              lateness and command_latency finite, step_wall finite and >= 0; each link sample's
//              answered_step in [0, step] (never an answer from the future), every lag finite,
//              injected_lag, round_trip and controller_round_trip >= 0 (one-way lags carry the
//              hosts' clock offset: any sign), prediction errors finite
//   footer     its counters.steps (the exchanges: steps 0 to it were recorded) against the steps:
//              steps after the highest intact one up to the count with no damaged region or cut
//              between it and the footer (lost steps), or steps beyond the count, are named
//   ending     no footer while the record did not end inside an entry: the record was cut between
//              two entries (`cut`), which a reader reports as it reports a truncation
// Loading only; allocates; never throws for what it reads.

#include <string>
#include <vector>

#include "runtime/record/record.h"

namespace rths::runtime {

inline constexpr int kMaxRecordDofs = 10000;

// Magnitudes no structure, actuator or ground motion reaches (SI): a value beyond one is a broken
// or forged record, whatever the study. A study's own limits, when set, are tighter.
inline constexpr double kPlausibleDisplacement = 1e3;  // m (u, command, realised)
inline constexpr double kPlausibleVelocity = 1e5;      // m/s
inline constexpr double kPlausibleAcceleration = 1e7;  // m/s^2 (a, ground acceleration)
inline constexpr double kPlausibleForce = 1e12;        // N

struct RecordChecks {
  std::vector<std::string> problems;  // header first, then in entry order
  bool fatal = false;  // the header cannot size a table: nothing may be built from the record
  bool cut = false;    // no footer and no truncation: the record stops between two entries
  bool ok() const { return problems.empty() && !cut; }
  // "N problems: <first>; <second>; ..." (at most `shown` listed, then "and M more").
  std::string summary(std::size_t shown = 10) const;
};

RecordChecks check_record(const RecordContents& contents);

}  // namespace rths::runtime
