// Records of rths's own distributed runs over Cyclone DDS (real coordinator and node processes on
// loopback, the shared DDS domain, each test on topics of its own), identified from the record: the run
// is launched with effects its config does not declare, injected by the nodes (their stages, and
// their links' network emulation: a drifting delay, periodic spikes, a burst of dropped commands),
// then the record's header is given the declared config (as a lab's record holds the config it
// meant to run). Each effect must be named on its own link, the clean records (lockstep and real
// time) name none, and the in-process re-run with the identified model reproduce the recorded
// response where the declared one is far off.
#include <gtest/gtest.h>

#include <cstdio>
#include <optional>
#include <set>
#include <string>

#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "runtime/launch/launch.h"
#include "tests/identify/undeclared_run.h"
#include "tests/support/dds_scope.h"
#include "tests/support/platform_gate.h"
#include "tests/support/real_time_run.h"

namespace rths::identify {
namespace {

namespace fs = std::filesystem;
using test::link_effects;

constexpr double kDuration = 5.0;  // s of the paper frame's motion

class DdsRunRecord : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

// A DDS run of case lag_shift_14ms whose node 1 and node 2 carry `node1` and `node2` (NodeSpec
// fields the declared config lacks); `fields` (deployment fields, e.g. the clock) are declared.
// The record's header then holds the declared config. A real-time run is launched beside a
// stall witness: `machine_stalled` says why, when a stall of this machine failed it rightly
// (tests/support/real_time_run.h), and the test is then skipped.
struct UndeclaredRun {
  fs::path record;
  std::optional<std::string> machine_stalled;
};
UndeclaredRun launch_undeclared(const std::string& name, const std::string& node1,
                                const std::string& node2, int domain,
                                const std::string& fields = "", double duration = kDuration) {
  const auto deployment = [&](const std::string& n1, const std::string& n2) {
    return "deployment { " + fields + " nodes { id: 1 kind: SUBSTRUCTURE " + n1 +
           " } nodes { id: 2 kind: ACTUATOR_EMULATOR " + n2 + " } }";
  };
  const test::WitnessedRun witnessed = test::launch_witnessed(
      name, test::paper_frame_study(duration, deployment(node1, node2)), "lag_shift_14ms", domain);
  const test::RealTimeVerdict verdict = test::real_time_verdict(witnessed);
  UndeclaredRun out;
  if (verdict.kind == test::RealTimeVerdict::kMachineStalled)
    out.machine_stalled = verdict.why;
  else
    EXPECT_EQ(verdict.kind, test::RealTimeVerdict::kCompleted) << verdict.why;
  const test::LaunchedRun& run = witnessed.run;
  const fs::path record = run.dir / "run.rthsrec";
  const study::PreparedStudy declared =
      test::prepare(test::paper_frame_study(duration, deployment("", "")));
  test::rewrite(record, [&](runtime::RecordEntry& e) {
    if (e.has_header()) *e.mutable_header()->mutable_study() = declared.config;
    if (e.has_inputs())
      *e.mutable_inputs()->mutable_study() = study::with_embedded_inputs(declared);
  });
  out.record = record;
  return out;
}

fs::path launch_with_undeclared(const std::string& name, const std::string& node1,
                                const std::string& node2, int domain,
                                const std::string& fields = "", double duration = kDuration) {
  return launch_undeclared(name, node1, node2, domain, fields, duration).record;
}

// A real-time run at the study's 1 kHz, with fail-safe windows wide enough that a loaded machine
// (or a burst of 12 dropped commands) does not stop it, and no overrun or answer-fraction verdict:
// these tests judge the record, not this machine's timing.
const std::string kRealTime =
    "clock: REAL_TIME max_overrun_fraction: -1 max_missed_answers: 40 "
    "command_watchdog_periods: 40 min_answer_fraction: -1";
constexpr double kRealTimeDuration = 3.0;  // s

// Network emulation on a node's receive lag (config NetworkEmulation fields).
std::string network(const std::string& fields) {
  return "receive_lag { network { " + fields + " } }";
}
const std::string kDrift = "drift_rate: 0.0006";  // 3 ms over the 5 s run
const std::string kSpikes = "spike_delay: 0.006 spike_every: 250 spike_steps: 3";

// The injected spikes (6 ms, 3 steps in every 250 at 1 kHz: 720 spiked steps a minute) are told
// apart from the machine's own only while the machine stalls past half their height far less
// often; measured first, else the test is skipped naming what the machine did.
std::optional<std::string> machine_masks_the_spikes() {
  const test::MeasuredPlatform machine = test::measure_platform(1000.0, 1.0);
  const double own = machine.stalls->stalls_per_minute(0.003);
  if (own <= 72.0) return std::nullopt;  // a tenth of the injected spiked steps
  return "this machine stalls past 3 ms " + std::to_string(static_cast<int>(own)) +
         " times a minute now (" + machine.text +
         "), too often to tell 720 injected spiked "
         "steps a minute from its own";
}

std::set<std::string> undeclared(const RunIdentification& run) {
  const auto& names = run.actuators.at(0).undeclared;
  return {names.begin(), names.end()};
}

IdentifyOptions actuator_only() {
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  return options;
}

TEST_F(DdsRunRecord, ACleanRecordNamesNothingAndReRunsAsRecorded) {
  const RunIdentification run = identify_run_record(
      launch_with_undeclared("identify_dds_clean", "", "", test::scope_dds_to_this_test()),
      actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(run.held.rfind("complete", 0), 0u) << text;
  EXPECT_TRUE(link_effects(run, 1).empty()) << text;
  EXPECT_TRUE(link_effects(run, 2).empty()) << text;
  ASSERT_EQ(run.actuators.size(), 1u);
  EXPECT_TRUE(run.actuators[0].undeclared.empty()) << text;
  ASSERT_TRUE(run.residual.has_value());
  EXPECT_LT(run.residual->declared, 1e-9) << text;  // lockstep equals in process bit for bit
}

TEST_F(DdsRunRecord, ALagOnOneLinkAndAFirstOrderLagOnTheActuatorAreEachNamedWhereTheyAre) {
  const RunIdentification run = identify_run_record(
      launch_with_undeclared("identify_dds_two", "receive_lag { one_way_delay: 0.001 }",
                             "receive_delay { first_order { time_constant: 0.008 } }",
                             test::scope_dds_to_this_test()),
      actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(link_effects(run, 1), std::set<std::string>{"injection"}) << text;
  EXPECT_TRUE(link_effects(run, 2).empty()) << text;
  ASSERT_EQ(run.actuators.size(), 1u);
  EXPECT_EQ(
      std::set<std::string>(run.actuators[0].undeclared.begin(), run.actuators[0].undeclared.end()),
      std::set<std::string>{"first_order"})
      << text;
  ASSERT_TRUE(run.residual.has_value());
  std::printf("DDS first order 8 ms + 1 ms lag on node 1: NRMSE declared %.4f -> identified %.6f\n",
              run.residual->declared, run.residual->identified);
  EXPECT_GE(run.residual->declared, 0.20) << text;
  EXPECT_LE(run.residual->identified, 0.02) << text;
}

// Network effects in lockstep do not reach the response: the re-run finds nothing to explain.
TEST_F(DdsRunRecord, ADriftOnOneLinkAndPeriodicSpikesOnTheOtherAreEachNamedWhereTheyAre) {
  if (const auto why = machine_masks_the_spikes()) GTEST_SKIP() << *why;
  test::StallWitness witness;
  const fs::path record = launch_with_undeclared("identify_dds_drift_spikes", network(kDrift),
                                                 network(kSpikes), test::scope_dds_to_this_test());
  const test::MeasuredPlatform machine = witness.finish();
  const RunIdentification run = identify_run_record(record, actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(link_effects(run, 1), std::set<std::string>{"drifting delay"}) << text;
  // The link's lag is read from the recorded round trips, which carry the machine's own wake-up
  // lateness too: 0.6 ms on a quiet machine, widened by what the machine's lateness spread
  // (its p99) was during this run.
  EXPECT_NEAR(run.links.at(0).drift_range, 0.003, 6e-4 + machine.p99) << text << machine.text;
  EXPECT_EQ(link_effects(run, 2), std::set<std::string>{"periodic spikes"}) << text;
  EXPECT_NEAR(run.links.at(1).spike_period, 0.25, 0.01) << text;
  EXPECT_TRUE(undeclared(run).empty()) << text;
  ASSERT_TRUE(run.residual.has_value());
  EXPECT_LT(run.residual->declared, 1e-9) << text;
}

TEST_F(DdsRunRecord, ADriftingDelayAndAnEmulatorGainErrorAreEachNamedWhereTheyAre) {
  const RunIdentification run = identify_run_record(
      launch_with_undeclared("identify_dds_drift_gain", network(kDrift),
                             "receive_delay { shift { delay: 0 } amplitude_gain: 1.08 }",
                             test::scope_dds_to_this_test()),
      actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(link_effects(run, 1), std::set<std::string>{"drifting delay"}) << text;
  EXPECT_TRUE(link_effects(run, 2).empty()) << text;
  EXPECT_EQ(undeclared(run), std::set<std::string>{"gain error"}) << text;
  ASSERT_TRUE(run.residual.has_value());
  std::printf("DDS drift on node 1 + gain 1.08: NRMSE declared %.4f -> identified %.6f\n",
              run.residual->declared, run.residual->identified);
  EXPECT_GE(run.residual->declared, 0.20) << text;
  EXPECT_LE(run.residual->identified, 0.02) << text;
}

TEST_F(DdsRunRecord, PeriodicSpikesAndAFirstOrderLagAreEachNamedWhereTheyAre) {
  if (const auto why = machine_masks_the_spikes()) GTEST_SKIP() << *why;
  const RunIdentification run = identify_run_record(
      launch_with_undeclared(
          "identify_dds_spikes_lag", "",
          network(kSpikes) + " receive_delay { first_order { time_constant: 0.008 } }",
          test::scope_dds_to_this_test()),
      actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_TRUE(link_effects(run, 1).empty()) << text;
  EXPECT_EQ(link_effects(run, 2), std::set<std::string>{"periodic spikes"}) << text;
  EXPECT_EQ(undeclared(run), std::set<std::string>{"first_order"}) << text;
  ASSERT_TRUE(run.residual.has_value());
  std::printf("DDS spikes on node 2 + first order 8 ms: NRMSE declared %.4f -> identified %.6f\n",
              run.residual->declared, run.residual->identified);
  EXPECT_GE(run.residual->declared, 0.20) << text;
  EXPECT_LE(run.residual->identified, 0.02) << text;
}

// In real time the loop may take a newer answer before an older one it also received: the
// record's answer count tells those apart from lost ones, so a clean run loses none.
TEST_F(DdsRunRecord, ACleanRealTimeRecordLosesNoAnswersAndNamesNothingOnItsLinks) {
  const UndeclaredRun launched =
      launch_undeclared("identify_dds_rt_clean", "", "", test::scope_dds_to_this_test(), kRealTime,
                        kRealTimeDuration);
  if (launched.machine_stalled) GTEST_SKIP() << *launched.machine_stalled;
  const RunIdentification run = identify_run_record(launched.record, actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(run.clock, "real_time") << text;
  // The platform's part is stated whatever this busy machine did: a real-time record is judged
  // by its overruns, and any it had lead the report.
  ASSERT_TRUE(run.platform.has_value()) << text;
  EXPECT_GT(run.platform->steps, 0u);
  if (run.platform->overruns > 0)
    EXPECT_NE(text.find("\nplatform: " + std::to_string(run.platform->overruns) + " of "),
              std::string::npos)
        << text;
  EXPECT_EQ(run_record_json(run)["platform"]["overruns"].get<std::uint64_t>(),
            run.platform->overruns);
  for (const NetworkPath& link : run.links) {
    std::printf("real time, clean: node %d lost %zu, superseded %zu, late %zu of %zu answers\n",
                link.node_id, link.lost, link.superseded, link.late, link.answers);
    EXPECT_EQ(link.lost, 0u) << text;
  }
  EXPECT_TRUE(link_effects(run, 1).empty()) << text;
  EXPECT_TRUE(link_effects(run, 2).empty()) << text;
}

TEST_F(DdsRunRecord, ARealTimeBurstOfDroppedCommandsIsNamedAsLostAnswersOnItsLink) {
  const UndeclaredRun launched =
      launch_undeclared("identify_dds_rt_burst", network("drop_first_step: 1000 drop_steps: 12"),
                        "", test::scope_dds_to_this_test(), kRealTime, kRealTimeDuration);
  if (launched.machine_stalled) GTEST_SKIP() << *launched.machine_stalled;
  const RunIdentification run = identify_run_record(launched.record, actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_EQ(link_effects(run, 1), std::set<std::string>{"lost answers"}) << text;
  EXPECT_EQ(run.links.at(0).lost, 12u) << text;
  EXPECT_EQ(run.links.at(0).longest_burst, 12u) << text;
  EXPECT_EQ(run.links.at(1).lost, 0u) << text;
  EXPECT_TRUE(link_effects(run, 2).count("lost answers") == 0) << text;
}

// The force stages (a specimen's own mass, a friction force beside it, a late load cell) in a
// case the emulator process runs over DDS in lockstep: the record equals the in-process run of the
// same config bit for bit, and the stages act (the run without them reads other forces).
TEST_F(DdsRunRecord, ForceStagesOverDdsEqualTheInProcessRunBitForBit) {
  const std::string stages =
      "delay { shift { delay: 0.014 } } delay { inertia_force { mass: 100 } } "
      "delay { friction_force { friction_force: 300 smoothing_velocity: 0.002 } } "
      "delay { force_delay { delay: 0.005 } }";
  const std::string text = test::paper_frame_study(
      2.0, "cases { name: \"force_stages\" " + stages + " }\n" + test::kDeclared);
  const core::SimulationResult in_process = test::reference_result(text, "force_stages");
  const core::SimulationResult without = test::reference_result(text, "lag_shift_14ms");
  EXPECT_NE(in_process.measured_force(1000, 0), without.measured_force(1000, 0));
  const auto run = test::launch("identify_dds_force_stages", text, "force_stages",
                                test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_FALSE(run.record.truncated);
  test::expect_record_equals(run.record, in_process);
}

// A specimen's own mass, undeclared, behind the actuator's shift in the emulator process over DDS
// (test::smooth_frame_study's motion): named on the specimen with its mass, and the re-run,
// holding it as an inertia_force stage, closes the record to <= 1 %.
TEST_F(DdsRunRecord, AnUndeclaredSpecimenMassIsNamedAndTheReRunClosesTheRecord) {
  const std::string declared = test::smooth_frame_study(test::kDeclared);
  const auto run = test::launch("identify_dds_inertia",
                                test::behind_the_shift(declared, "inertia_force { mass: 100 }"),
                                "lag_shift_14ms", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  const fs::path record = run.dir / "run.rthsrec";
  const study::PreparedStudy as_declared = test::prepare(declared);
  test::rewrite(record, [&](runtime::RecordEntry& e) {
    if (e.has_header()) *e.mutable_header()->mutable_study() = as_declared.config;
    if (e.has_inputs())
      *e.mutable_inputs()->mutable_study() = study::with_embedded_inputs(as_declared);
  });
  const RunIdentification id = identify_run_record(record, IdentifyOptions{});
  const std::string text = run_record_text(id);
  const Finding* inertia = nullptr;
  for (const auto& f : id.findings)
    if (f.part == "specimen 1" && f.effect == "inertia") inertia = &f;
  ASSERT_NE(inertia, nullptr) << text;
  ASSERT_EQ(inertia->parameters.size(), 1u);
  EXPECT_NEAR(inertia->parameters[0].value, 100.0, 5.0) << text;
  ASSERT_TRUE(id.residual.has_value());
  std::printf("DDS specimen mass 100 kg: NRMSE declared %.4f -> identified %.6f\n",
              id.residual->declared, id.residual->identified);
  EXPECT_GE(id.residual->declared, 0.05) << text;
  EXPECT_LE(id.residual->identified, 0.01) << text;
  ASSERT_TRUE(inertia->response_removed.has_value()) << inertia->not_rerun;
  EXPECT_GT(inertia->response_share, 0.5) << text;
}

}  // namespace
}  // namespace rths::identify
