// check_record (runtime/record/record_checks.h): records whose checksums hold but whose meaning
// does not are named entry by entry; a header that cannot size a table is fatal; a record that
// stops between two entries without its footer reads as cut.
#include "runtime/record/record_checks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "runtime/node/schema.h"
#include "util/crc32c.h"

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

// The attack's CRC-valid nonsense, each written with valid checksums: each is named.
RecordEntry header_dt(double dt) {
  RecordEntry e = header();
  e.mutable_header()->set_dt(dt);
  return e;
}

TEST(RecordChecks, ADtThatIsNoTimeStepIsNamed) {
  for (double dt : {std::numeric_limits<double>::quiet_NaN(), 0.0, -1.0}) {
    const RecordChecks checks =
        check_record(record_of({header_dt(dt), step(0), step(1), footer()}));
    ASSERT_FALSE(checks.ok()) << dt;
    EXPECT_THAT(checks.problems[0], HasSubstr("entry 0 (header): dt "));
    EXPECT_THAT(checks.problems[0], HasSubstr(" s is not a time step (finite, > 0)"));
  }
}

TEST(RecordChecks, AGapNoDamagedRegionExplainsIsNamed) {
  const RecordChecks checks =
      check_record(record_of({header(), step(0), step(1), step(1000000002), footer()}));
  ASSERT_EQ(checks.problems.size(), 1u) << checks.summary();
  EXPECT_THAT(checks.problems[0],
              HasSubstr("entry 3 (step 1000000002): steps 2-1000000001 are absent before it with "
                        "no damaged region where they would be (a gap in the sequence)"));
}

TEST(RecordChecks, TimeGoingBackOrOffStepTimesDtIsNamedAsOneRegion) {
  std::vector<RecordEntry> entries{header()};
  for (int k = 0; k < 10; ++k) {
    entries.push_back(step(k));
    if (k >= 3 && k <= 7) entries.back().mutable_step()->set_time(0.5 + 0.01 * k);
  }
  entries.push_back(step(10));
  entries.back().mutable_step()->set_time(0.05);
  entries.push_back(footer());
  const RecordChecks checks = check_record(record_of(entries));
  ASSERT_EQ(checks.problems.size(), 4u) << checks.summary();
  EXPECT_THAT(checks.problems[0], HasSubstr("entries 4-8 (steps 3-7, 5 steps): time 0.53 s is not "
                                            "step x dt (3 x 0.01 s = 0.03 s)"));
  EXPECT_THAT(checks.problems[1], HasSubstr("entry 9 (step 8): time 0.08 s is before the step "
                                            "before's 0.57 s (time goes back)"));
  EXPECT_THAT(checks.problems[2], HasSubstr("entry 11 (step 10): time 0.05 s is before"));
  EXPECT_THAT(checks.problems[3], HasSubstr("entry 11 (step 10): time 0.05 s is not step x dt"));
}

TEST(RecordChecks, ValuesBeyondPlausibleOrTheDeploymentsLimitsAreNamed) {
  const RecordChecks wild = check_record(record_of({header(), step(0), step(1, 1e300), footer()}));
  ASSERT_EQ(wild.problems.size(), 1u) << wild.summary();
  EXPECT_THAT(
      wild.problems[0],
      HasSubstr("entry 2 (step 1): displacement[0] = 1e+300 m is beyond a plausible 1000 m"));
  RecordEntry inputs;
  inputs.mutable_inputs()
      ->mutable_study()
      ->mutable_deployment()
      ->mutable_limits()
      ->set_max_displacement(0.5);
  const RecordChecks limited = check_record(
      record_of({header(), inputs, step(0), step(1, 0.4), step(2, 0.6), step(3, 0.7), footer()}));
  ASSERT_EQ(limited.problems.size(), 1u) << limited.summary();
  EXPECT_THAT(limited.problems[0],
              HasSubstr("entries 4-5 (steps 2-3, 2 steps): displacement[0] = 0.6 m is beyond the "
                        "deployment's max_displacement 0.5 m"));
}

TEST(RecordChecks, HeaderCopiesThatDisagreeAreNamed) {
  const RecordChecks checks =
      check_record(record_of({header(), header(), step(0), header_dt(0.02), step(1), footer()}));
  ASSERT_EQ(checks.problems.size(), 1u) << checks.summary();
  EXPECT_THAT(checks.problems[0], HasSubstr("entry 3 (header copy): disagrees with the header in "
                                            "entry 0: modified: dt: 0.01 -> 0.02"));
}

// Each header copy names the run's inputs entry by its CRC-32C: another inputs entry is named.
TEST(RecordChecks, AnInputsEntryThatIsNotTheOneTheHeaderNamesIsNamed) {
  RecordEntry inputs;
  inputs.mutable_inputs()->mutable_study()->set_name("the run's");
  const std::string framed = inputs.SerializeAsString();
  RecordEntry named = header();
  named.mutable_header()->set_inputs_crc32c(util::crc32c(framed.data(), framed.size()));
  EXPECT_TRUE(check_record(record_of({named, inputs, step(0), footer()})).ok());
  inputs.mutable_inputs()->mutable_study()->set_name("another run's");
  const RecordChecks swapped = check_record(record_of({named, inputs, step(0), footer()}));
  ASSERT_EQ(swapped.problems.size(), 1u) << swapped.summary();
  EXPECT_THAT(swapped.problems[0], HasSubstr("entry 1 (inputs): its CRC-32C "));
  EXPECT_THAT(swapped.problems[0], HasSubstr("(inputs that are not the run's)"));
}

RecordEntry counted_footer(std::uint64_t exchanges) {
  RecordEntry e = footer();
  e.mutable_footer()->mutable_counters()->set_steps(exchanges);
  return e;
}

// Steps 0 to `last` (but those in [cut_from, cut_to]), then a footer counting `exchanges`.
std::vector<RecordEntry> counted_run(std::int64_t last, std::uint64_t exchanges,
                                     std::int64_t cut_from = -1, std::int64_t cut_to = -1) {
  std::vector<RecordEntry> entries{header()};
  for (std::int64_t k = 0; k <= last; ++k)
    if (k < cut_from || k > cut_to) entries.push_back(step(k));
  entries.push_back(counted_footer(exchanges));
  return entries;
}

// The attack's record: steps 1000-1999 cut out cleanly (checksums intact) before the footer.
TEST(RecordChecks, StepsTheFooterCountsThatAreAbsentAreNamedAsLost) {
  EXPECT_TRUE(check_record(record_of(counted_run(1999, 1999))).ok());
  const RecordChecks lost = check_record(record_of(counted_run(1999, 1999, 1000, 1999)));
  ASSERT_EQ(lost.problems.size(), 1u) << lost.summary();
  EXPECT_THAT(lost.problems[0],
              HasSubstr("entry 1001 (footer): counts 1999 exchanges (steps 0-1999) and the last "
                        "intact step is 999: steps 1000-1999 are absent with no damaged region "
                        "where they would be (lost steps)"));
  const RecordChecks beyond = check_record(record_of(counted_run(20, 9)));
  ASSERT_EQ(beyond.problems.size(), 1u) << beyond.summary();
  EXPECT_THAT(beyond.problems[0], HasSubstr("counts 9 exchanges (steps 0-9) but the record holds "
                                            "step 20: steps the run did not make"));
}

// Steps a damaged region may have held are the reader's loss report, not a problem.
TEST(RecordChecks, StepsADamagedRegionMayHaveHeldAreNotNamedAgain) {
  const std::vector<RecordEntry> entries = counted_run(9, 9);
  std::string bytes(record_preamble());
  for (std::size_t i = 0; i + 1 < entries.size(); ++i) append_record_frame(entries[i], bytes);
  bytes[bytes.size() - 3] ^= 0x40;  // step 9's payload
  append_record_frame(entries.back(), bytes);
  const RecordContents damaged = parse_record(bytes, "damaged.rthsrec");
  ASSERT_TRUE(damaged.lost_entries());
  EXPECT_TRUE(check_record(damaged).ok()) << check_record(damaged).summary();
}

TEST(RecordChecks, AnInputsEntryTheHeaderNamesThatIsAbsentIsNamed) {
  RecordEntry named = header();
  named.mutable_header()->set_inputs_crc32c(0x1234abcd);
  const RecordChecks checks = check_record(record_of({named, step(0), footer()}));
  ASSERT_EQ(checks.problems.size(), 1u) << checks.summary();
  EXPECT_THAT(checks.problems[0],
              HasSubstr("no inputs entry: the header names one (CRC-32C 1234abcd) and no damaged "
                        "region lies where it would be (before the first step)"));
}

// Steps 0-2, then step 3 (entry 4) with `link` its only link sample.
RecordChecks checks_with_link(const LinkSample& link) {
  RecordEntry s = step(3);
  *s.mutable_step()->add_links() = link;
  return check_record(record_of({header(), step(0), step(1), step(2), s, footer()}));
}

LinkSample sound_link() {
  LinkSample link;
  link.set_node_id(7);
  link.set_answered_step(2);
  link.set_round_trip(1e-4);
  link.set_one_way_down(-2e-5);  // across hosts: the clocks' offset
  return link;
}

TEST(RecordChecks, LinkSamplesOutOfTheirRangeAreNamed) {
  EXPECT_TRUE(checks_with_link(sound_link()).ok()) << checks_with_link(sound_link()).summary();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<LinkSample, std::string>> cases;
  LinkSample link = sound_link();
  link.set_round_trip(nan);
  cases.emplace_back(link, "links[0] (node 7): round_trip is not finite");
  link = sound_link();
  link.set_one_way_up(std::numeric_limits<double>::infinity());
  cases.emplace_back(link, "links[0] (node 7): one_way_up is not finite");
  link = sound_link();
  link.set_injected_lag(-0.5);
  cases.emplace_back(link, "links[0] (node 7): injected_lag -0.5 s is negative");
  link = sound_link();
  link.set_controller_round_trip(-1e-3);
  cases.emplace_back(link, "links[0] (node 7): controller_round_trip -0.001 s is negative");
  link = sound_link();
  link.set_answered_step(4);
  cases.emplace_back(
      link, "links[0] (node 7): answered_step 4 is after this step (an answer from the future)");
  link = sound_link();
  link.set_answered_step(-1);
  cases.emplace_back(link, "links[0] (node 7): answered_step -1 is negative");
  link = sound_link();
  link.add_prediction_error(nan);
  cases.emplace_back(link, "links[0] (node 7): prediction_error[0] is not finite");
  for (const auto& [bad, named] : cases) {
    const RecordChecks checks = checks_with_link(bad);
    ASSERT_EQ(checks.problems.size(), 1u) << named << ": " << checks.summary();
    EXPECT_THAT(checks.problems[0], HasSubstr("entry 4 (step 3): " + named));
  }
}

TEST(RecordChecks, TimingsThatAreNoTimeAreNamed) {
  std::vector<RecordEntry> entries{header()};
  for (int k = 0; k < 4; ++k) entries.push_back(step(k));
  entries[2].mutable_step()->set_lateness(std::numeric_limits<double>::quiet_NaN());
  entries[3].mutable_step()->set_lateness(std::numeric_limits<double>::quiet_NaN());
  entries[4].mutable_step()->set_step_wall(-1e-3);
  entries[4].mutable_step()->set_lateness(-2e-4);  // early: fine
  entries.push_back(footer());
  const RecordChecks checks = check_record(record_of(entries));
  ASSERT_EQ(checks.problems.size(), 2u) << checks.summary();
  EXPECT_THAT(checks.problems[0],
              HasSubstr("entries 2-3 (steps 1-2, 2 steps): lateness is not finite"));
  EXPECT_THAT(checks.problems[1],
              HasSubstr("entry 4 (step 3): step_wall -0.001 s is not a time span (finite, >= 0)"));
}

// recorded_dofs name each step's columns: a DOF outside the model or out of order is fatal, as a
// header that cannot size a table is; a step with another count of values is named.
TEST(RecordChecks, RecordedDofsOutsideTheModelOrOutOfOrderAreFatal) {
  RecordEntry kept = header(500, 1);
  kept.mutable_header()->add_recorded_dofs(0);
  kept.mutable_header()->add_recorded_dofs(499);
  EXPECT_TRUE(check_record(record_of({kept, step(0), step(1), footer()})).ok());
  for (const std::vector<int>& bad : {std::vector<int>{0, 500}, {7, 3}, {-1, 2}, {4, 4}}) {
    RecordEntry h = header(500, 1);
    for (const int dof : bad) h.mutable_header()->add_recorded_dofs(dof);
    const RecordChecks checks = check_record(record_of({h, step(0), footer()}));
    EXPECT_TRUE(checks.fatal) << bad[0] << " " << bad[1];
    EXPECT_THAT(checks.summary(), HasSubstr("is not a DOF of 0..499 above the one before it"));
  }
  RecordEntry three = header(500, 1);
  for (const int dof : {0, 250, 499}) three.mutable_header()->add_recorded_dofs(dof);
  EXPECT_THAT(check_record(record_of({three, step(0), footer()})).summary(),
              HasSubstr("displacement has 2 values, not 3"));
}

}  // namespace
}  // namespace rths::runtime
