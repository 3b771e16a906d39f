#include "runtime/record/measurements.h"

#include <gtest/gtest.h>

#include <vector>

namespace rths::runtime {
namespace {

// A real-time record of 6 steps, 1 DOF, 1 actuator, links to nodes 1 and 2. Node 2's answers
// arrive late and are reused: it answers steps 0 (none yet), 1, 1, 3, 3, 5 at steps 0..5.
RecordContents real_time_record() {
  RecordContents r;
  RecordEntry header;
  header.mutable_header()->set_clock("real_time");
  header.mutable_header()->set_case_name("lag");
  header.mutable_header()->set_dt(0.001);
  header.mutable_header()->set_dofs(1);
  header.mutable_header()->set_actuators(1);
  header.mutable_header()->add_link_node_ids(1);
  header.mutable_header()->add_link_node_ids(2);
  r.entries.push_back(header);
  const std::int64_t answers_of_2[] = {0, 1, 1, 3, 3, 5};
  for (int k = 0; k < 6; ++k) {
    RecordEntry e;
    StepRecord& s = *e.mutable_step();
    s.set_step(k);
    s.set_time(0.001 * k);
    s.add_displacement(0.01 * k);
    s.add_velocity(0.1 * k);
    s.add_acceleration(1.0 * k);
    s.add_command(0.02 * k);
    s.add_realised(0.015 * k);
    s.add_measured_force(100.0 * k);
    if (k > 0) {
      LinkSample& one = *s.add_links();
      one.set_node_id(1);
      one.set_answered_step(k);
      one.set_round_trip(1e-4 * k);
      LinkSample& two = *s.add_links();
      two.set_node_id(2);
      two.set_answered_step(answers_of_2[k]);
      two.set_answers(static_cast<std::uint64_t>(answers_of_2[k]));  // 2 and 4 arrived too
      two.set_round_trip(0.002 + 1e-4 * k);  // a repeat carries the same sample in a real record
      two.set_injected_lag(0.0015);
    }
    r.entries.push_back(e);
  }
  RecordEntry footer;
  footer.mutable_footer()->set_ok(true);
  footer.mutable_footer()->set_status("completed");
  r.entries.push_back(footer);
  return r;
}

TEST(Measurements, PerStepColumnsComeFromEveryStep) {
  const RunMeasurements m = measure_run(real_time_record());
  EXPECT_EQ(m.clock, "real_time");
  EXPECT_EQ(m.case_name, "lag");
  ASSERT_EQ(m.steps.steps(), 6u);
  EXPECT_DOUBLE_EQ(m.steps.dt, 0.001);
  EXPECT_DOUBLE_EQ(m.steps.displacement(4, 0), 0.04);
  EXPECT_DOUBLE_EQ(m.steps.velocity(4, 0), 0.4);
  EXPECT_DOUBLE_EQ(m.steps.command(5, 0), 0.1);
  EXPECT_DOUBLE_EQ(m.steps.realised(5, 0), 0.075);
  EXPECT_DOUBLE_EQ(m.steps.measured_force(2, 0), 200.0);
  EXPECT_TRUE(m.has_footer);
  EXPECT_EQ(m.footer.status(), "completed");
}

TEST(Measurements, EachAnswerCountsOnceAtTheFirstStepThatCarriesIt) {
  const RunMeasurements m = measure_run(real_time_record());
  ASSERT_EQ(m.links.size(), 2u);
  const LinkSeries& one = m.links.at(1);
  EXPECT_EQ(one.answered_step, (std::vector<std::int64_t>{1, 2, 3, 4, 5}));
  const LinkSeries& two = m.links.at(2);
  EXPECT_EQ(two.answered_step, (std::vector<std::int64_t>{1, 3, 5}));
  EXPECT_EQ(two.time, (std::vector<double>{0.001, 0.003, 0.005}));
  EXPECT_EQ(two.answers, (std::vector<std::int64_t>{1, 3, 5}));  // the coordinator's count
  EXPECT_EQ(two.round_trip_summary().count, 3u);
  EXPECT_DOUBLE_EQ(two.round_trip_summary().median, 0.002 + 3e-4);
  EXPECT_DOUBLE_EQ(two.injected_summary().mean, 0.0015);
}

TEST(Measurements, TheLiveAccumulatorAgreesWithTheReader) {
  const RecordContents record = real_time_record();
  LinkLagAccumulator live;
  for (const StepRecord* s : record.steps())
    for (const LinkSample& link : s->links()) live.add(s->time(), link);
  const RunMeasurements m = measure_run(record);
  for (const auto& [id, series] : m.links) {
    EXPECT_EQ(live.links().at(id).answered_step, series.answered_step);
    EXPECT_EQ(live.links().at(id).answers, series.answers);
    EXPECT_EQ(live.links().at(id).round_trip, series.round_trip);
  }
}

TEST(Measurements, ARecordWithoutHeaderIsRefused) {
  RecordContents empty;
  EXPECT_THROW(measure_run(empty), std::invalid_argument);
}

TEST(Measurements, ARecordCutShortSaysSo) {
  RecordContents r = real_time_record();
  r.entries.pop_back();
  const RunMeasurements m = measure_run(r);
  EXPECT_FALSE(m.has_footer);
  EXPECT_EQ(m.steps.steps(), 6u);
}

// A large model's record keeps the DOFs its recorders asked for (RunHeader.recorded_dofs): the
// measurements hold those columns and say which DOF each is.
TEST(Measurements, RecordedDofsAreTheColumnsAndNameTheirDofs) {
  RecordContents r = real_time_record();
  RunHeader& h = *r.entries.front().mutable_header();
  h.set_dofs(500);
  h.add_recorded_dofs(0);
  h.add_recorded_dofs(499);
  for (RecordEntry& e : r.entries)
    if (e.has_step()) e.mutable_step()->add_displacement(-e.step().displacement(0));
  const RunMeasurements m = measure_run(r);
  ASSERT_EQ(m.steps.displacement.cols(), 2);
  EXPECT_EQ(m.steps.dofs, (std::vector<int>{0, 499}));
  EXPECT_EQ(m.steps.column_of_dof(499), 1);
  EXPECT_EQ(m.steps.column_of_dof(250), -1);
  EXPECT_DOUBLE_EQ(m.steps.displacement(4, 1), -0.04);
}

}  // namespace
}  // namespace rths::runtime
