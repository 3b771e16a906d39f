// results/results: a record's table (export, read_record) has the CSV's variable names, SI units
// and NaN where a value is missing.
#include "results/results.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>

#include "study/motion_key.h"
#include "study/study.h"

namespace rths::results {
namespace {

std::vector<std::string> names(const Table& t) {
  std::vector<std::string> out;
  for (const auto& c : t.columns()) out.push_back(c.name);
  return out;
}

TEST(ResultsTest, RecordTableHasTheExportColumnsAndNanForStepZerosLink) {
  runtime::RecordContents record;
  runtime::RecordEntry header_entry;
  auto* header = header_entry.mutable_header();
  header->set_dofs(1);
  header->set_actuators(1);
  header->add_link_node_ids(2);
  header->set_case_name("lag");
  record.entries.push_back(header_entry);
  for (int k = 0; k < 2; ++k) {
    runtime::RecordEntry e;
    auto* s = e.mutable_step();
    s->set_step(k);
    s->set_time(0.001 * k);
    s->add_displacement(0.5 * k);
    s->add_velocity(1);
    s->add_acceleration(2);
    s->add_command(3);
    s->add_realised(4);
    s->add_measured_force(5);
    if (k > 0) {
      auto* link = s->add_links();
      link->set_answered_step(k);
      link->set_round_trip(0.0002);
    }
    s->set_overrun(k == 1);
    record.entries.push_back(e);
  }
  const Table t = record_table(record);
  EXPECT_EQ(names(t),
            (std::vector<std::string>{
                "step", "time_s", "ground_acceleration_m_per_s2", "u_floor1_m", "v_floor1_m_per_s",
                "a_floor1_m_per_s2", "command_act1_m", "measured_act1_m", "force_act1_N",
                "node2_answered_step", "node2_injected_lag_s", "node2_round_trip_s",
                "node2_one_way_down_s", "node2_one_way_up_s", "lateness_s", "overrun"}));
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_TRUE(std::isnan(t.column("node2_round_trip_s").numbers[0]));
  EXPECT_DOUBLE_EQ(t.column("node2_round_trip_s").numbers[1], 0.0002);
  EXPECT_EQ(t.column("node2_round_trip_s").unit, "s");
  EXPECT_EQ(t.column("a_floor1_m_per_s2").unit, "m/s^2");
  EXPECT_DOUBLE_EQ(t.column("u_floor1_m").numbers[1], 0.5);
  EXPECT_DOUBLE_EQ(t.column("measured_act1_m").numbers[1], 4.0);
  EXPECT_EQ(t.column("overrun").numbers, (std::vector<double>{0, 1}));
  EXPECT_EQ(t.attributes().at("status"), "no footer: the run was cut short");
  EXPECT_EQ(t.number_attributes().at("ok"), 0.0);
  EXPECT_THROW(record_table(runtime::RecordContents{}), std::invalid_argument);
}

TEST(ResultsTest, RecordTableCarriesTheStudyStepMotionAsRunAndTheFootersVerdict) {
  runtime::RecordContents record;
  runtime::RecordEntry header_entry;
  auto* header = header_entry.mutable_header();
  header->set_dofs(1);
  header->set_actuators(0);
  header->set_dt(0.002);
  header->mutable_study()->set_name("frame");
  header->mutable_study()->mutable_motion()->set_path("/data/RSN175.AT2");
  header->mutable_study()->mutable_motion()->set_sha256(std::string(64, 'c'));
  record.entries.push_back(header_entry);
  runtime::RecordEntry step;
  step.mutable_step()->add_displacement(0);
  record.entries.push_back(step);
  const Table without_inputs = record_table(record);
  EXPECT_EQ(without_inputs.attributes().at("study"), "frame");
  EXPECT_DOUBLE_EQ(without_inputs.number_attributes().at("dt_s"), 0.002);
  EXPECT_EQ(without_inputs.attributes().at("motion_name"), "") << "the record has no motion";
  EXPECT_EQ(without_inputs.attributes().at("motion_sha256"), "");
  EXPECT_EQ(without_inputs.attributes().at("motion_file_sha256"), std::string(64, 'c'));

  runtime::RecordEntry inputs;
  *inputs.mutable_inputs()->mutable_study() = header->study();
  auto* embedded = inputs.mutable_inputs()->mutable_study()->mutable_motion()->mutable_embedded();
  embedded->set_name("RSN175");
  embedded->set_dt(0.002);
  embedded->add_acceleration(0.5);
  embedded->add_acceleration(-0.25);
  embedded->set_source_sha256(std::string(64, 'd'));
  record.entries.insert(record.entries.begin() + 1, inputs);
  runtime::RecordEntry footer;
  footer.mutable_footer()->set_ok(true);
  footer.mutable_footer()->set_status("completed");
  record.entries.push_back(footer);
  const Table t = record_table(record);
  EXPECT_EQ(t.attributes().at("motion_name"), "RSN175");
  const core::GroundMotion as_run{.name = "RSN175", .dt = 0.002, .acceleration = {0.5, -0.25}};
  EXPECT_EQ(t.attributes().at("motion_sha256"), study::motion_key(as_run));
  EXPECT_EQ(t.attributes().at("motion_sha256").size(), 64u);
  EXPECT_EQ(t.attributes().at("motion_file_sha256"), std::string(64, 'd'));
  EXPECT_EQ(t.attributes().at("status"), "completed");
  EXPECT_EQ(t.number_attributes().at("ok"), 1.0);
}

// A record of one DOF and one actuator, links to nodes 1 and 2, three steps; `links` fills each
// step after the first (step k) with its link samples. `header` may add to the header.
runtime::RecordContents two_link_record(
    const std::function<void(runtime::StepRecord&, int)>& links,
    const std::function<void(runtime::RunHeader&)>& header = {}) {
  runtime::RecordContents record;
  runtime::RecordEntry header_entry;
  auto* h = header_entry.mutable_header();
  h->set_dofs(1);
  h->set_actuators(1);
  h->add_link_node_ids(1);
  h->add_link_node_ids(2);
  if (header) header(*h);
  record.entries.push_back(header_entry);
  for (int k = 0; k < 3; ++k) {
    runtime::RecordEntry e;
    auto* s = e.mutable_step();
    s->set_step(k);
    s->add_displacement(0);
    s->add_velocity(0);
    s->add_acceleration(0);
    s->add_command(0);
    s->add_realised(0);
    s->add_measured_force(0);
    if (k > 0) links(*s, k);
    record.entries.push_back(e);
  }
  return record;
}

// A link with a force predictor carries its model's error per step: the export gives it a
// column per actuator of the node, after the link's one-way lags; a link without one has none.
TEST(ResultsTest, RecordTableGivesAPredictedLinkItsPredictionError) {
  const runtime::RecordContents record = two_link_record([](runtime::StepRecord& s, int k) {
    s.add_links()->add_prediction_error(12.5 * k);
    s.add_links()->set_answered_step(k);
  });
  const Table t = record_table(record);
  const std::vector<std::string> all = names(t);
  const auto at = [&all](const std::string& name) {
    return std::find(all.begin(), all.end(), name) - all.begin();
  };
  ASSERT_LT(at("node1_prediction_error1_N"), static_cast<long>(all.size()));
  EXPECT_EQ(at("node1_prediction_error1_N"), at("node1_one_way_up_s") + 1);
  EXPECT_EQ(at("node2_prediction_error1_N"), static_cast<long>(all.size()));
  const auto& error = t.column("node1_prediction_error1_N");
  EXPECT_EQ(error.unit, "N");
  EXPECT_TRUE(std::isnan(error.numbers[0]));
  EXPECT_DOUBLE_EQ(error.numbers[2], 25.0);
}

TEST(ResultsTest, RecordTableGivesAControllerNodesLinkItsFrameRoundTripAndStatus) {
  const runtime::RecordContents record = two_link_record(
      [](runtime::StepRecord& s, int k) {
        s.add_links()->set_answered_step(k);
        auto* link = s.add_links();
        link->set_answered_step(k);
        link->set_controller_round_trip(0.0001 * k);
        link->set_controller_status(k == 2 ? 7 : 0);
      },
      [](runtime::RunHeader& h) {
        auto* controller = h.mutable_study()->mutable_deployment()->add_nodes();
        controller->set_id(2);
        controller->set_kind(config::NodeSpec::CONTROLLER);
      });
  const Table t = record_table(record);
  const std::vector<std::string> all = names(t);
  const auto at = [&all](const std::string& name) {
    return std::find(all.begin(), all.end(), name) - all.begin();
  };
  EXPECT_EQ(at("node1_controller_round_trip_s"), static_cast<long>(all.size()))
      << "node 1 is no controller";
  ASSERT_LT(at("node2_controller_status"), static_cast<long>(all.size()));
  EXPECT_EQ(at("node2_controller_round_trip_s"), at("node2_one_way_up_s") + 1);
  EXPECT_EQ(at("node2_controller_status"), at("node2_one_way_up_s") + 2);
  const auto& rtt = t.column("node2_controller_round_trip_s");
  EXPECT_EQ(rtt.unit, "s");
  EXPECT_TRUE(std::isnan(rtt.numbers[0]));
  EXPECT_DOUBLE_EQ(rtt.numbers[2], 0.0002);
  EXPECT_EQ(t.column("node2_controller_status").numbers[1], 0.0);
  EXPECT_EQ(t.column("node2_controller_status").numbers[2], 7.0);
}

// A record that keeps some DOFs (RunHeader.recorded_dofs) names each column by its DOF.
TEST(ResultsTest, RecordTableNamesARecordedDofsColumnsByTheirDof) {
  runtime::RecordContents record;
  runtime::RecordEntry header_entry;
  auto* header = header_entry.mutable_header();
  header->set_dofs(2000);
  header->set_actuators(0);
  header->add_recorded_dofs(0);
  header->add_recorded_dofs(1999);
  record.entries.push_back(header_entry);
  runtime::RecordEntry e;
  auto* s = e.mutable_step();
  for (double u : {0.25, 0.75}) {
    s->add_displacement(u);
    s->add_velocity(2 * u);
    s->add_acceleration(4 * u);
  }
  record.entries.push_back(e);
  const Table t = record_table(record);
  EXPECT_EQ(t.column("u_floor1_m").numbers, (std::vector<double>{0.25}));
  EXPECT_EQ(t.column("u_floor2000_m").numbers, (std::vector<double>{0.75}));
  EXPECT_EQ(t.column("a_floor2000_m_per_s2").numbers, (std::vector<double>{3.0}));
  EXPECT_THROW(t.column("u_floor2_m"), std::out_of_range);
}

}  // namespace
}  // namespace rths::results
