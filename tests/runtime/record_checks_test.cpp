// check_record (runtime/record/record_checks.h): records whose checksums hold but whose meaning
// does not are named entry by entry; a header that cannot size a table is fatal; a record that
// stops between two entries without its footer reads as cut.
#include "runtime/record/record_checks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "runtime/node/schema.h"

namespace rths::runtime {
namespace {

using testing::HasSubstr;

RecordEntry header(int dofs = 2, int actuators = 1) {
  RecordEntry e;
  e.mutable_header()->set_schema_version(kSchemaVersion);
  e.mutable_header()->set_dt(0.01);
  e.mutable_header()->set_dofs(dofs);
  e.mutable_header()->set_actuators(actuators);
  return e;
}

RecordEntry step(std::int64_t k, double u = 0.0) {
  RecordEntry e;
  StepRecord& s = *e.mutable_step();
  s.set_step(k);
  s.set_time(0.01 * static_cast<double>(k));
  for (int d = 0; d < 2; ++d) {
    s.add_displacement(u);
    s.add_velocity(0.0);
    s.add_acceleration(0.0);
  }
  s.add_command(0.0);
  s.add_realised(0.0);
  s.add_measured_force(0.0);
  return e;
}

RecordEntry footer() {
  RecordEntry e;
  e.mutable_footer()->set_ok(true);
  e.mutable_footer()->set_status("completed");
  return e;
}

// The bytes of a record with these entries, read back as read_record would.
RecordContents record_of(const std::vector<RecordEntry>& entries) {
  std::string bytes(record_preamble());
  for (const RecordEntry& e : entries) append_record_frame(e, bytes);
  return parse_record(bytes, "crafted.rthsrec");
}

TEST(RecordChecks, AnOrdinaryRecordHasNoProblem) {
  const RecordChecks checks = check_record(record_of({header(), step(0), step(1), footer()}));
  EXPECT_TRUE(checks.ok()) << checks.summary();
  EXPECT_FALSE(checks.fatal);
}

TEST(RecordChecks, AnUnknownSchemaVersionIsNamed) {
  RecordEntry h = header();
  h.mutable_header()->set_schema_version(999);
  const RecordChecks checks = check_record(record_of({h, step(0), footer()}));
  EXPECT_THAT(checks.summary(), HasSubstr("entry 0 (header): schema version 999"));
  EXPECT_FALSE(checks.fatal);
}

TEST(RecordChecks, DuplicatedAndReversedStepsAreNamedWithTheirEntry) {
  const RecordChecks checks =
      check_record(record_of({header(), step(0), step(1), step(1), step(3), step(2), footer()}));
  ASSERT_EQ(checks.problems.size(), 4u) << checks.summary();
  EXPECT_THAT(checks.problems[0], HasSubstr("entry 3 (step 1): comes after step 1 (a duplicate)"));
  EXPECT_THAT(checks.problems[1], HasSubstr("entry 4 (step 3): steps 2-2 are absent before it"));
  EXPECT_THAT(checks.problems[2], HasSubstr("entry 5 (step 2): comes after step 3 (out of order)"));
  EXPECT_THAT(checks.problems[3], HasSubstr("entry 5 (step 2): time 0.02 s is before"));
}

TEST(RecordChecks, ValuesNotFiniteAndSizesThatDisagreeWithTheHeaderAreNamed) {
  RecordEntry short_step = step(2);
  short_step.mutable_step()->mutable_velocity()->RemoveLast();
  const RecordChecks checks =
      check_record(record_of({header(), step(0), step(1, std::numeric_limits<double>::quiet_NaN()),
                              short_step, footer()}));
  ASSERT_EQ(checks.problems.size(), 2u) << checks.summary();
  EXPECT_THAT(checks.problems[0], HasSubstr("entry 2 (step 1): displacement[0] is not finite"));
  EXPECT_THAT(checks.problems[1], HasSubstr("entry 3 (step 2): velocity has 1 values, not 2"));
}

TEST(RecordChecks, AHeaderThatCannotSizeATableIsFatal) {
  for (int dofs : {-1, 0, 100000}) {
    const RecordChecks checks = check_record(record_of({header(dofs, 0), step(0), footer()}));
    EXPECT_TRUE(checks.fatal) << dofs;
    EXPECT_THAT(checks.summary(), HasSubstr("dofs " + std::to_string(dofs) + " outside [1, "));
  }
  EXPECT_TRUE(check_record(record_of({header(2, 3), footer()})).fatal);
  EXPECT_TRUE(check_record(record_of({footer()})).fatal) << "no header, no step";
}

// Without a header the steps are read with one assumed from them, which is named.
TEST(RecordChecks, ARecordWithoutHeaderIsReadWithTheAssumedOneNamed) {
  const RecordChecks checks = check_record(record_of({step(0), step(1), step(2), footer()}));
  EXPECT_FALSE(checks.fatal);
  ASSERT_EQ(checks.problems.size(), 1u) << checks.summary();
  EXPECT_THAT(checks.problems[0],
              HasSubstr("no intact header entry: crafted.rthsrec: no intact header (every copy "
                        "damaged or missing): read with one assumed from the steps: dofs 2 and "
                        "actuators 1 (the step frames' sizes), dt 0.01 s (the step times)"));
}

TEST(RecordChecks, ARecordCutBetweenTwoEntriesReadsAsCut) {
  const RecordChecks cut = check_record(record_of({header(), step(0), step(1)}));
  EXPECT_TRUE(cut.cut);
  EXPECT_FALSE(cut.ok());
  EXPECT_THAT(cut.summary(), HasSubstr("no footer"));
  EXPECT_FALSE(check_record(record_of({header(), step(0), footer()})).cut);
}

}  // namespace
}  // namespace rths::runtime
