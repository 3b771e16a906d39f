// A distributed run identified from its record. The records come from rths's own distributed
// runs (coordinator + node services in one process, tests/support): the run is made with an
// effect its config does not declare (a node stage on the actuator emulator), then the record's
// header is given the declared config, as a lab's record holds the config it meant to run. Each
// effect must be named on the right link or actuator, a clean record must name none, a truncated
// record identifies what it holds, and bad records are refused naming record, entry and problem.
// Network effects (a drifting delay, periodic spikes, lost answers) need the nodes' link emulation,
// which runs in node processes: dds_run_record_test.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "runtime/record/record.h"
#include "tests/identify/undeclared_run.h"

namespace rths::identify {
namespace {

namespace fs = std::filesystem;
using test::link_effects;
using test::rewrite;
using test::run_with_undeclared;
using test::scratch;

IdentifyOptions actuator_only() {
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  return options;
}

std::set<std::string> undeclared(const RunIdentification& run, int actuator) {
  const auto& names = run.actuators.at(static_cast<std::size_t>(actuator - 1)).undeclared;
  return {names.begin(), names.end()};
}

TEST(RunRecord, ACleanRunNamesNothing) {
  const fs::path record = run_with_undeclared("clean", "");
  const RunIdentification run = identify_run_record(record, actuator_only());
  EXPECT_EQ(run.held.rfind("complete", 0), 0u) << run.held;
  ASSERT_EQ(run.actuators.size(), 1u);
  EXPECT_TRUE(undeclared(run, 1).empty()) << run_record_text(run);
  EXPECT_TRUE(link_effects(run, 1).empty()) << run_record_text(run);
  EXPECT_TRUE(link_effects(run, 2).empty()) << run_record_text(run);
}

TEST(RunRecord, AnExtraActuatorFirstOrderLagIsNamedOnTheActuator) {
  const fs::path record =
      run_with_undeclared("first_order", "receive_delay { first_order { time_constant: 0.008 } }");
  const RunIdentification run = identify_run_record(record, actuator_only());
  EXPECT_TRUE(undeclared(run, 1).count("first_order")) << run_record_text(run);
  EXPECT_TRUE(link_effects(run, 2).empty()) << run_record_text(run);
  const EffectEstimate* lag = run.actuators.at(0).estimate(Channel::kMeasured, Effect::kFirstOrder);
  ASSERT_NE(lag, nullptr) << run_record_text(run);
  ASSERT_EQ(lag->parameters.size(), 1u);
  EXPECT_NEAR(lag->parameters[0].value, 0.008, 0.0008) << run_record_text(run);
}

TEST(RunRecord, AnEmulatorGainErrorIsNamedOnTheActuator) {
  const fs::path record =
      run_with_undeclared("gain", "receive_delay { shift { delay: 0 } amplitude_gain: 1.08 }");
  const RunIdentification run = identify_run_record(record, actuator_only());
  EXPECT_EQ(undeclared(run, 1), std::set<std::string>{"gain error"}) << run_record_text(run);
  EXPECT_NEAR(run.actuators[0].fitted_gain, 1.08, 0.01);
}

// A velocity limit behind a first-order lag, both declared in the header, on a record long
// enough that the search runs decimated: the declared model is fitted from the declared values
// (jointly, and again at the full rate), so nothing is named. Before, the delay fitted alone
// took up the lag and the limit, and a false delay change or gain error was named.
TEST(RunRecord, ADeclaredVelocityLimitBehindALagIsNotNamedOnALongRecord) {
  const std::string study = test::paper_frame_study(
      30.0,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR "
      "receive_delay { first_order { time_constant: 0.008 } } "
      "receive_delay { velocity_limit { max_velocity: 0.05 } } } }");
  const fs::path record =
      test::record_declaring("declared_velocity_limit", study, study, "lag_shift_14ms", true);
  const RunIdentification run = identify_run_record(record, actuator_only());
  ASSERT_GT(run.actuators.at(0).id.search_decimation, 1u);
  EXPECT_TRUE(undeclared(run, 1).empty()) << run_record_text(run);
  EXPECT_NEAR(run.actuators.at(0).fitted_delay, 0.014, 1e-4) << run_record_text(run);
}

// The RTHS benchmark's case 1 as configs/ holds it (15 s of it): a declared tracking loop around
// the benchmark plant, with sensor noise and the load cell one servo period late. Its record
// names nothing: the plant's specimen inertia and damping and the load cell's delay are the
// loop's, the sensors' noise is the declared, and the re-run keeps the declared loop (a fitted
// delay and gain in its place missed the response by 10 %).
TEST(RunRecord, ADeclaredTrackingLoopIsNotContradictedByItsOwnRecord) {
  const std::string dir = std::string(RTHS_DATA_DIR) + "/../configs/benchmark/";
  std::ifstream in(dir + "case_1.textproto");
  std::string study((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const std::string file : {"case_1.mat", "el_centro.txt"})
    for (auto at = study.find('"' + file); at != std::string::npos;
         at = study.find('"' + file, at + dir.size()))
      study.insert(at + 1, dir);
  study.replace(study.find("motion { "), 9, "motion { duration: 15 ");
  const fs::path record =
      test::record_declaring("declared_tracking_loop", study, study, "sample_controller", true);
  const RunIdentification run = identify_run_record(record, IdentifyOptions{});
  const std::string text = run_record_text(run);
  const ActuatorPath& path = run.actuators.at(0);
  EXPECT_TRUE(path.undeclared.empty()) << text;
  EXPECT_TRUE(path.specimen_undeclared.empty()) << text;
  EXPECT_NEAR(path.displacement_noise, path.declared_displacement_noise,
              0.1 * path.declared_displacement_noise)
      << text;
  EXPECT_NEAR(path.force_noise, path.declared_force_noise, 0.1 * path.declared_force_noise) << text;
  ASSERT_TRUE(run.residual.has_value());
  EXPECT_LT(run.residual->identified, 1e-9) << text;
  // Nothing left above the floor its sensors' noise sets (residual_floor.h), on either channel.
  ASSERT_EQ(run.floors.size(), 2u) << text;
  for (const auto& f : run.floors) EXPECT_FALSE(f.above) << f.text() << "\n" << text;
}

TEST(RunRecord, ATruncatedRecordIdentifiesWhatItHoldsAndSaysSo) {
  const fs::path record = run_with_undeclared("truncated", "");
  fs::resize_file(record, fs::file_size(record) / 2 + 3);
  const RunIdentification run = identify_run_record(record, actuator_only());
  EXPECT_EQ(run.held.rfind("truncated", 0), 0u) << run.held;
  EXPECT_GT(run.steps, 4000u);
  EXPECT_LT(run.steps, 6000u);
}

TEST(RunRecord, ADivergedRunIsIdentifiedUpToItsDivergenceAndSaysSo) {
  // 100 ms more lag than declared: the paper frame's hybrid loop goes unstable.
  const fs::path record = run_with_undeclared("diverged", "receive_delay { shift { delay: 0.1 } }",
                                              "lag_shift_14ms", 25.0, false);
  const RunIdentification run = identify_run_record(record, actuator_only());
  EXPECT_EQ(run.held.rfind("diverged", 0), 0u) << run.held;
  EXPECT_NE(run.held.find("identified up to step " + std::to_string(run.steps)), std::string::npos)
      << run.held;
  EXPECT_TRUE(undeclared(run, 1).count("delay change")) << run_record_text(run);
  EXPECT_NEAR(run.actuators.at(0).fitted_delay, 0.114, 1e-3) << run_record_text(run);
}

void expect_refused(const fs::path& record, const std::string& entry, const std::string& problem) {
  try {
    identify_run_record(record, actuator_only());
    FAIL() << "no throw for " << entry;
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(record.string()), std::string::npos) << what;
    EXPECT_NE(what.find(entry), std::string::npos) << what;
    EXPECT_NE(what.find(problem), std::string::npos) << what;
  }
}

TEST(RunRecord, BadRecordsAreRefusedNamingRecordEntryAndProblem) {
  const fs::path record = run_with_undeclared("bad", "");
  const fs::path other_version = scratch("other_version");
  fs::copy_file(record, other_version, fs::copy_options::overwrite_existing);
  rewrite(other_version, [](runtime::RecordEntry& e) {
    if (e.has_header()) e.mutable_header()->set_schema_version(99);
  });
  expect_refused(other_version, "header", "schema version 99");
  const fs::path missing_link = scratch("missing_link");
  fs::copy_file(record, missing_link, fs::copy_options::overwrite_existing);
  rewrite(missing_link, [](runtime::RecordEntry& e) {
    if (e.has_header()) e.mutable_header()->add_link_node_ids(9);
  });
  expect_refused(missing_link, "link to node 9", "0 answers");
  const fs::path damaged = scratch("damaged");
  fs::copy_file(record, damaged, fs::copy_options::overwrite_existing);
  {
    std::fstream bytes(damaged, std::ios::in | std::ios::out | std::ios::binary);
    bytes.seekp(static_cast<std::streamoff>(fs::file_size(damaged) / 2));
    bytes.put('\x5a').put('\xa5').put('\x5a');
  }
  expect_refused(damaged, "damaged entries", "");
  const fs::path not_a_record = scratch("not_a_record");
  std::ofstream(not_a_record) << "time,command\n";
  expect_refused(not_a_record, "", "");
}

}  // namespace
}  // namespace rths::identify
