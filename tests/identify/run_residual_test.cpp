// The system-level residual of a distributed run: the study re-run in process with the declared and
// with the identified actuators, each against the recorded response. Records from rths's own
// distributed runs (tests/identify/undeclared_run.h) with an actuator effect the config does not
// declare: the declared model must be off by >= 20 % NRMSE and the identified one reproduce the
// record to <= 2 %; a clean record re-runs exactly; the effect explaining the error is named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>

#include "core/metrics.h"
#include "identify/model/study_config.h"
#include "identify/run/findings.h"
#include "identify/run/run_config.h"
#include "identify/run/run_record.h"
#include "identify/run/run_record_format.h"
#include "runtime/record/record.h"
#include "tests/identify/undeclared_run.h"

namespace rths::identify {
namespace {

IdentifyOptions actuator_only() {
  IdentifyOptions options;
  options.channels = {Channel::kMeasured};
  return options;
}

const RunResidual& residual_of(const RunIdentification& run) {
  EXPECT_TRUE(run.residual.has_value());
  static const RunResidual none;
  return run.residual ? *run.residual : none;
}

// The floor NRMSEs, on stdout for the report of the figures.
void print(const std::string& name, const RunResidual& r) {
  std::printf("%s: worst floor NRMSE declared %.4f -> identified %.4f over %zu steps\n",
              name.c_str(), r.declared, r.identified, r.steps);
}

TEST(RunResidual, ACleanRecordReRunsAsRecorded) {
  const RunIdentification run =
      identify_run_record(test::run_with_undeclared("residual_clean", ""), actuator_only());
  const RunResidual& r = residual_of(run);
  print("clean", r);
  ASSERT_EQ(r.floors.size(), 1u);
  EXPECT_EQ(r.steps, run.steps);
  EXPECT_LT(r.declared, 1e-9) << run_record_text(run);
  EXPECT_LT(r.identified, 0.02) << run_record_text(run);
  EXPECT_TRUE(r.effects.empty());
}

// A model past study::kAllDofsLimit: its record keeps the DOFs its recorders keep
// (RunHeader.recorded_dofs; the defaults: DOFs 1, n/4, n/2, 3n/4 and the top). Each recorded
// column is compared with the re-run's response of the DOF it holds and named by that DOF, so a
// clean record re-runs as recorded on every floor it holds.
TEST(RunResidual, ALargeModelsRecordIsComparedWithTheDofsItHolds) {
  const std::string study = test::uniform_storeys_study(250, 4e9, 5.0) + test::kDeclared;
  const RunIdentification run = identify_run_record(
      test::record_declaring("residual_storeys250", study, study, "reference", true),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("250 DOFs, clean", r);
  const std::vector<int> kept = test::prepare(study).recorders.kept_dofs;
  ASSERT_GT(kept.size(), 2u);
  ASSERT_EQ(r.floors.size(), kept.size()) << run_record_text(run);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    EXPECT_EQ(r.floors[i].dof, kept[i] + 1) << run_record_text(run);
    EXPECT_LT(r.floors[i].declared, 1e-9) << "DOF " << kept[i] + 1 << "\n" << run_record_text(run);
  }
  EXPECT_EQ(r.declared_response.cols(), static_cast<Eigen::Index>(kept.size()));
  EXPECT_NE(run_record_text(run).find(" floor 250 "), std::string::npos) << run_record_text(run);
}

TEST(RunResidual, AnExtraFirstOrderLagIsReproducedByTheIdentifiedModel) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_first_order",
                                "receive_delay { first_order { time_constant: 0.008 } }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("first order 8 ms", r);
  EXPECT_GE(r.declared, 0.20) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  ASSERT_EQ(r.links.size(), 1u);
  EXPECT_NEAR(r.links[0].share, 1.0, 1e-12);
  EXPECT_NEAR(r.links[0].removed, r.declared - r.identified, 1e-12);
  ASSERT_FALSE(r.effects.empty()) << run_record_text(run);
  EXPECT_EQ(r.effects[0].effect, "first_order") << run_record_text(run);
  EXPECT_GT(r.effects[0].share, 0.9) << run_record_text(run);
}

TEST(RunResidual, AnEmulatorGainErrorIsReproducedAndNamedAsTheCause) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_gain",
                                "receive_delay { shift { delay: 0 } amplitude_gain: 1.25 }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("gain 1.25", r);
  EXPECT_GE(r.declared, 0.20) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  ASSERT_EQ(r.effects.size(), 1u) << run_record_text(run);
  EXPECT_EQ(r.effects[0].effect, "gain error");
  EXPECT_NEAR(r.effects[0].share, 1.0, 1e-12);
}

TEST(RunResidual, AnUndeclaredExtraDelayIsNamedAsADelayChangeAndReproduced) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_delay", "receive_delay { shift { delay: 0.006 } }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("extra delay 6 ms", r);
  EXPECT_NEAR(run.actuators.at(0).fitted_delay, 0.020, 2e-4) << run_record_text(run);
  EXPECT_GE(r.declared, 0.20) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  ASSERT_EQ(r.effects.size(), 1u) << run_record_text(run);
  EXPECT_EQ(r.effects[0].effect, "delay change");
  EXPECT_NEAR(r.effects[0].share, 1.0, 1e-12);
}

// A lag where the run declared none: case "reference" declares no actuator stage and the
// emulator delays every command by 6 steps. The declared delay is 0, so the fitted one is a
// finding ("delay change: 0 -> 6 ms") in the actuator section and the verdict, the re-run holds it
// and closes the record, and the written study holds it as a shift.
TEST(RunResidual, ALagWhereNoActuatorStageWasDeclaredIsADelayChangeFromZero) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_undeclared_lag",
                                "receive_delay { shift { delay: 0.006 } }", "reference"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("6 ms lag, none declared", r);
  const std::string text = run_record_text(run);
  const ActuatorPath& path = run.actuators.at(0);
  EXPECT_TRUE(path.delay_declared) << text;
  EXPECT_EQ(path.declared_delay, 0.0) << text;
  EXPECT_NEAR(path.fitted_delay, 0.006, 2e-4) << text;
  EXPECT_NE(text.find(", delay 0 ms (fitted 6"), std::string::npos) << text;
  EXPECT_NE(text.find("actuator 1: delay change: 0 -> 6"), std::string::npos) << text;
  ASSERT_EQ(r.effects.size(), 1u) << text;
  EXPECT_EQ(r.effects[0].effect, "delay change");
  EXPECT_GE(r.declared, 0.05) << text;
  EXPECT_LE(r.identified, 0.1 * r.declared) << text;
  const IdentifiedRun written = identified_run(run, ".", std::filesystem::temp_directory_path());
  const config::Case* identified = study::case_named(written.study, kIdentifiedCaseName);
  ASSERT_NE(identified, nullptr);
  double shift = 0.0;
  for (const auto& stage : identified->delay())
    if (stage.has_shift()) shift += stage.shift().delay();
  EXPECT_NEAR(shift, 0.006, 2e-4) << identified->DebugString();
}

// The same run without the lag: its fitted delay is the declared 0, nothing is named.
TEST(RunResidual, ARunDeclaringNoActuatorStageWithoutALagNamesNoDelayChange) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_no_lag", "", "reference"), actuator_only());
  const std::string text = run_record_text(run);
  EXPECT_TRUE(run.actuators.at(0).delay_declared) << text;
  EXPECT_TRUE(run.actuators.at(0).undeclared.empty()) << text;
  EXPECT_LT(residual_of(run).identified, 0.02) << text;
}

// The re-run keeps only what helps, the selection alone with the removals given: the most
// negative removal is rejected first (its part, channel and the NRMSE it added), one per pass,
// the study re-run after each rejection only; a removal within round-off (-kMinErrorRemoved) and
// a positive one are kept.
TEST(RunResidual, TheReRunKeepsOnlyTheEffectsThatHelp) {
  RunIdentification run;
  run.actuators.emplace_back();
  ActuatorPath& path = run.actuators.back();
  path.actuator = 1;
  path.undeclared = {"first_order", "gain error"};
  path.specimen_undeclared = {"bouc_wen", "damping"};
  const double round_off = -0.5 * kMinErrorRemoved;
  RunResidual first, second, third;
  first.effects = {{"actuator 1", "first_order", 0.3, 0.0},
                   {"actuator 1", "gain error", -0.2, 0.0},
                   {"specimen 1", "bouc_wen", -0.994, 0.0},
                   {"specimen 1", "damping", round_off, 0.0}};
  second.effects = {{"actuator 1", "first_order", 0.3, 0.0},
                    {"actuator 1", "gain error", -0.01, 0.0},
                    {"specimen 1", "damping", round_off, 0.0}};
  third.effects = {{"actuator 1", "first_order", 0.31, 0.0},
                   {"specimen 1", "damping", round_off, 0.0}};
  run.residual = first;
  const std::vector<RunResidual> reruns{second, third};
  std::size_t made = 0;
  keep_what_helps(run, [&] { return reruns.at(made++); });
  EXPECT_EQ(made, 2u);
  EXPECT_EQ(path.undeclared, std::vector<std::string>{"first_order"});
  EXPECT_EQ(path.specimen_undeclared, std::vector<std::string>{"damping"});
  ASSERT_EQ(path.rejected.size(), 2u);
  EXPECT_EQ(path.rejected[0].part, "specimen 1");
  EXPECT_EQ(path.rejected[0].effect, "bouc_wen");
  EXPECT_EQ(path.rejected[0].channel, Channel::kForce);
  EXPECT_DOUBLE_EQ(path.rejected[0].worsening, 0.994);
  EXPECT_EQ(path.rejected[1].effect, "gain error");
  EXPECT_EQ(path.rejected[1].channel, Channel::kMeasured);
  EXPECT_DOUBLE_EQ(path.rejected[1].worsening, 0.01);
  EXPECT_NE(run_record_text(run).find(
                "specimen 1: bouc_wen rejected: makes the re-run's NRMSE worse by 99.4 %"),
            std::string::npos)
      << run_record_text(run);
}

// The re-run never ends worse than the declared model, with the re-runs given as functions of
// what stands named: every named effect together leaves 2 % over the whole record where the
// declared model leaves 1 % (no removal negative: each looked like help on top of the rest). The
// re-run falls back to the declared model; of the effects each put back, only the first order
// lowers the whole record's error and is kept, the gain error and the bouc_wen are rejected with
// that reason, the moving parameters (worse here) stay out, and the notes say it fell back.
TEST(RunResidual, AReRunWorseThanTheDeclaredFallsBackToWhatLowersItsError) {
  RunIdentification run;
  run.actuators.emplace_back();
  ActuatorPath& path = run.actuators.back();
  path.actuator = 1;
  path.undeclared = {"first_order", "gain error", "noise"};
  path.specimen_undeclared = {"bouc_wen"};
  const auto named = [&](const std::vector<std::string>& list, const std::string& effect) {
    return std::find(list.begin(), list.end(), effect) != list.end();
  };
  const auto rerun = [&] {
    RunResidual r;
    r.declared = 0.01;
    r.identified = 0.01;
    if (named(path.undeclared, "first_order")) r.identified -= 0.004;
    if (named(path.undeclared, "gain error")) r.identified += 0.002;
    if (named(path.specimen_undeclared, "bouc_wen")) r.identified += 0.01;
    if (run.hold_moving) r.identified += 0.001;
    r.effects = {{"actuator 1", "first_order", 0.004, 0.0}};
    return r;
  };
  run.residual = rerun();
  ASSERT_NEAR(run.residual->identified, 0.019, 1e-12);
  keep_what_helps(run, rerun);
  EXPECT_NEAR(run.residual->identified, 0.006, 1e-12);
  EXPECT_EQ(path.undeclared, (std::vector<std::string>{"noise", "first_order"}));
  EXPECT_TRUE(path.specimen_undeclared.empty());
  EXPECT_FALSE(run.hold_moving);
  ASSERT_EQ(path.rejected.size(), 2u);
  EXPECT_EQ(path.rejected[0].effect, "gain error");
  EXPECT_NEAR(path.rejected[0].worsening, 0.002, 1e-12);
  EXPECT_EQ(path.rejected[1].effect, "bouc_wen");
  EXPECT_EQ(path.rejected[1].part, "specimen 1");
  EXPECT_EQ(path.rejected[1].channel, Channel::kForce);
  for (const auto& r : path.rejected)
    EXPECT_NE(r.reason.find("left 1.9 % over the whole record, the declared model 1 %"),
              std::string::npos)
        << r.reason;
  ASSERT_FALSE(run.residual->notes.empty());
  EXPECT_NE(run.residual->notes.back().find("re-run from the declared model with only what lowers "
                                            "it (actuator 1: first_order)"),
            std::string::npos)
      << run.residual->notes.back();
}

// The study of `record` re-run with `run`'s actuator paths as they stand (as identify_run_record
// makes it: the record's own ground acceleration, its recorded response).
RunResidual rerun_of(const std::filesystem::path& record, const RunIdentification& run,
                     const core::Mat& recorded) {
  const runtime::RecordContents contents = runtime::read_record(record);
  ResidualInput input;
  input.study = &run.study;
  input.case_name = run.case_name;
  input.clock = run.clock;
  input.base_dir = record.parent_path();
  input.motion.name = record.stem().string();
  input.motion.dt = run.study.integrator().dt();
  for (const runtime::StepRecord* step : contents.steps()) {
    if (input.motion.acceleration.size() == run.steps) break;
    input.motion.acceleration.push_back(step->ground_acceleration());
  }
  input.recorded = &recorded;
  input.actuators = &run.actuators;
  input.unexplained = &run.unexplained;
  return run_residual(input);
}

// A named effect that makes the re-run worse is rejected with real re-runs: the record of an
// 8 ms first-order lag, identified, then given a gain error of 1.3 in its fitted actuator as if
// its channel had named one (a fit gone wrong). The re-run with it misses the response; it is
// rejected, the lag kept, the re-run closes the record as before and the written study holds the
// lag without the gain.
TEST(RunResidual, ANamedEffectThatMakesTheReRunWorseIsRejected) {
  const std::filesystem::path record = test::run_with_undeclared(
      "residual_rejected", "receive_delay { first_order { time_constant: 0.008 } }");
  RunIdentification run = identify_run_record(record, actuator_only());
  const double closed = residual_of(run).identified;
  const core::Mat recorded = run.residual->recorded_response;
  ActuatorPath& path = run.actuators.at(0);
  ASSERT_EQ(path.undeclared, std::vector<std::string>{"first_order"}) << run_record_text(run);
  for (ChannelIdentification& c : path.id.channels) {
    if (c.channel != Channel::kMeasured) continue;
    const SignalScales scales = signal_scales(identified_signals(path.id, c.channel));
    const auto gain = c.final_fit.model.index_of(std::nullopt, "gain", scales);
    ASSERT_TRUE(gain.has_value());
    c.final_fit.model.params[*gain] = 1.3 * path.declared_gain;
  }
  path.undeclared.push_back("gain error");
  const auto rerun = [&] { return rerun_of(record, run, recorded); };
  run.residual = rerun();
  const double worse = run.residual->identified;
  print("first order 8 ms, a wrong gain named", *run.residual);
  ASSERT_GT(worse, closed + 0.05) << run_record_text(run);
  keep_what_helps(run, rerun);
  ASSERT_EQ(path.rejected.size(), 1u) << run_record_text(run);
  EXPECT_EQ(path.rejected[0].part, "actuator 1");
  EXPECT_EQ(path.rejected[0].effect, "gain error");
  EXPECT_NEAR(path.rejected[0].worsening, worse - closed, 1e-3);
  EXPECT_EQ(path.undeclared, std::vector<std::string>{"first_order"});
  EXPECT_NEAR(run.residual->identified, closed, 1e-3) << run_record_text(run);
  const IdentifiedRun written = identified_run(run, ".", std::filesystem::temp_directory_path());
  const config::Case* identified = study::case_named(written.study, kIdentifiedCaseName);
  ASSERT_NE(identified, nullptr);
  bool lag = false;
  for (const auto& stage : identified->delay()) {
    lag = lag || stage.has_first_order();
    const double gain = stage.amplitude_gain();  // 0: unset, a gain of 1
    EXPECT_TRUE(gain == 0.0 || std::abs(gain - 1.0) < 0.02) << identified->DebugString();
  }
  EXPECT_TRUE(lag) << identified->DebugString();
}

// The finding of `effect` on `part` in the one verdict over every part, or nullptr.
const Finding* finding(const std::vector<Finding>& findings, const std::string& part,
                       const std::string& effect) {
  for (const auto& f : findings)
    if (f.part == part && f.effect == effect) return &f;
  return nullptr;
}

TEST(RunResidual, AVelocityLimitIsReRunAndRemovesTheErrorItCaused) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_velocity_limit",
                                "receive_delay { velocity_limit { max_velocity: 0.05 } }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("velocity limit 50 mm/s", r);
  EXPECT_GE(r.declared, 0.05) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  const auto findings = collect_findings(run.links, run.actuators, &*run.residual, run.clock);
  const Finding* f = finding(findings, "actuator 1", "velocity_saturation");
  ASSERT_NE(f, nullptr) << run_record_text(run);
  ASSERT_EQ(f->parameters.size(), 1u);
  EXPECT_NEAR(f->parameters[0].value, 0.05, 0.005) << run_record_text(run);
  ASSERT_TRUE(f->response_removed.has_value()) << f->not_rerun;
  EXPECT_GT(*f->response_removed, 0.5 * (r.declared - r.identified)) << run_record_text(run);
}

TEST(RunResidual, BacklashIsReRun) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_backlash", "receive_delay { backlash { width: 0.002 } }"),
      actuator_only());
  const RunResidual& r = residual_of(run);
  print("backlash 2 mm", r);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  const auto findings = collect_findings(run.links, run.actuators, &*run.residual, run.clock);
  const Finding* f = finding(findings, "actuator 1", "backlash");
  ASSERT_NE(f, nullptr) << run_record_text(run);
  EXPECT_NEAR(f->parameters.at(0).value, 0.002, 0.0002) << run_record_text(run);
  EXPECT_TRUE(f->response_removed.has_value()) << f->not_rerun;
}

TEST(RunResidual, ALoadCellOffsetIsNamedOnTheLoadCellAndReRun) {
  const RunIdentification run = identify_run_record(
      test::run_with_undeclared("residual_load_cell",
                                "receive_delay { sensor_drift { force_offset: 500 } }"),
      IdentifyOptions{});
  const RunResidual& r = residual_of(run);
  print("load cell offset 500 N", r);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  const auto findings = collect_findings(run.links, run.actuators, &*run.residual, run.clock);
  const Finding* f = finding(findings, "load cell 1", "offset_drift");
  ASSERT_NE(f, nullptr) << run_record_text(run);
  ASSERT_TRUE(f->response_removed.has_value()) << f->not_rerun;
  EXPECT_GT(*f->response_removed, 0.0) << run_record_text(run);
}

TEST(RunResidual, AHystereticSpecimenDeclaredLinearIsNamedOnTheSpecimenAndReRun) {
  // The whole storey is the specimen (no numerical part), so that only the rig differs from the
  // declared study: a Bouc-Wen specimen where the header declares a linear one.
  std::string declared =
      test::paper_frame_study(10.0, "deployment { nodes { id: 2 kind: ACTUATOR_EMULATOR } }");
  const std::string fraction = "experimental_fraction: 0.3333333333333333";
  declared.replace(declared.find(fraction), fraction.size(), "experimental_storeys: 1");
  std::string actual = declared;
  const std::string linear = "model { linear {} }";
  actual.replace(actual.find(linear), linear.size(),
                 "model { bouc_wen { yield_displacement: 0.004 alpha: 0.1 n: 1 beta: 0.5 } }");
  const RunIdentification run = identify_run_record(
      test::record_declaring("residual_bouc_wen", actual, declared, "lag_shift_14ms", true),
      IdentifyOptions{});
  const RunResidual& r = residual_of(run);
  print("Bouc-Wen specimen", r);
  const auto findings = collect_findings(run.links, run.actuators, &*run.residual, run.clock);
  const Finding* f = finding(findings, "specimen 1", "bouc_wen");
  ASSERT_NE(f, nullptr) << run_record_text(run);
  ASSERT_TRUE(f->response_removed.has_value()) << f->not_rerun;
  EXPECT_GE(r.declared, 0.20) << run_record_text(run);
  EXPECT_LE(r.identified, 0.02) << run_record_text(run);
  EXPECT_EQ(finding(findings, "specimen 1", "stiffness change"), nullptr) << run_record_text(run);
}

// An effect on the force channel the header does not declare, put into the run's case behind the
// actuator's 14 ms shift (where it acts on the specimen's motion): named on its part with its
// magnitude (within 5 %), held by the re-run (a force stage of the identified case), so that the
// re-run closes the record to <= 1 % of the worst floor's NRMSE, and its share of the removals,
// measured by re-running without it, is most of them (never 0 %).
struct ForceEffect {
  std::string name, stage, part, effect, parameter, stage_kind;
  double value = 0.0;
  bool smooth = false;  // test::smooth_frame_study, else the paper frame's record
};

void expect_re_run_holds(const ForceEffect& c) {
  const std::string declared = c.smooth ? test::smooth_frame_study(test::kDeclared)
                                        : test::paper_frame_study(10.0, test::kDeclared);
  const std::string actual = test::behind_the_shift(declared, c.stage);
  const RunIdentification run = identify_run_record(
      test::record_declaring(c.name, actual, declared, "lag_shift_14ms", true), IdentifyOptions{});
  const RunResidual& r = residual_of(run);
  print(c.name, r);
  const std::string text = run_record_text(run);
  const Finding* f = finding(run.findings, c.part, c.effect);
  ASSERT_NE(f, nullptr) << text;
  double read = std::nan("");
  for (const auto& p : f->parameters)
    if (p.name == c.parameter) read = p.value;
  EXPECT_NEAR(read, c.value, 0.05 * c.value) << text;
  std::printf("%s: %s %s read %.6g (put in %.6g); share %.3g\n", c.name.c_str(), c.effect.c_str(),
              c.parameter.c_str(), read, c.value, f->response_share);
  EXPECT_GE(r.declared, 0.05) << text;
  EXPECT_LE(r.identified, 0.01) << text;
  ASSERT_TRUE(f->response_removed.has_value()) << f->not_rerun << "\n" << text;
  EXPECT_GT(*f->response_removed, 0.5 * (r.declared - r.identified)) << text;
  EXPECT_GT(f->response_share, 0.5) << text;
  for (const auto& note : r.notes)
    EXPECT_EQ(note.find(c.effect + ":"), std::string::npos) << note << "\n" << text;
  // The written study (identified_run.textproto) holds it as its force stage and, run in process,
  // closes the record as the re-run does.
  const IdentifiedRun written = identified_run(run, ".", std::filesystem::temp_directory_path());
  const config::Case* identified = study::case_named(written.study, kIdentifiedCaseName);
  ASSERT_NE(identified, nullptr);
  bool holds = false;
  for (const auto& stage : identified->delay()) {
    const auto* kind = stage.GetDescriptor()->FindFieldByNumber(stage.kind_case());
    holds = holds || (kind && kind->name() == c.stage_kind);
  }
  EXPECT_TRUE(holds) << c.stage_kind << " not in " << identified->DebugString();
  const study::PreparedStudy prepared = study::prepare_study(written.study, ".");
  const core::SimulationResult rerun =
      core::simulate(study::setup_for_case(prepared, *identified), prepared.motion);
  const auto n = static_cast<Eigen::Index>(r.steps);
  const Eigen::VectorXd recorded = r.recorded_response.col(0).head(n);
  const Eigen::VectorXd simulated = rerun.displacement.col(0).head(n);
  EXPECT_LE(core::nrmse(std::span<const double>(recorded.data(), r.steps),
                        std::span<const double>(simulated.data(), r.steps)),
            0.01);
}

TEST(RunResidual, ASpecimensOwnMassIsReRunAsAnInertiaForce) {
  expect_re_run_holds({"residual_inertia", "inertia_force { mass: 100 }", "specimen 1", "inertia",
                       "mass", "inertia_force", 100.0, true});
}

TEST(RunResidual, AFrictionForceBesideTheSpecimenIsReRun) {
  expect_re_run_holds(
      {"residual_friction", "friction_force { friction_force: 100 smoothing_velocity: 0.005 }",
       "specimen 1", "coulomb_friction", "friction_force", "friction_force", 100.0});
}

TEST(RunResidual, ALateLoadCellIsNamedOnTheLoadCellAndReRunAsAForceDelay) {
  expect_re_run_holds({"residual_force_delay", "force_delay { delay: 0.005 }", "load cell 1",
                       "delay", "delay", "force_delay", 0.005});
}

// A specimen mass the header declares (inertia_force in its case) with a first-order lag it does
// not: only the lag is named, and the re-run, whose identified actuator stages replace the
// declared ones, keeps the declared mass and closes the record.
TEST(RunResidual, ADeclaredSpecimenMassIsNotNamedAndStaysWhenTheActuatorIsReplaced) {
  const std::string declared = test::behind_the_shift(test::smooth_frame_study(test::kDeclared),
                                                      "inertia_force { mass: 100 }");
  std::string actual = declared;
  const std::string emulator = "kind: ACTUATOR_EMULATOR";
  actual.insert(actual.find(emulator) + emulator.size(),
                " receive_delay { first_order { time_constant: 0.008 } }");
  const RunIdentification run = identify_run_record(
      test::record_declaring("residual_declared_mass", actual, declared, "lag_shift_14ms", true),
      IdentifyOptions{});
  const RunResidual& r = residual_of(run);
  print("declared mass, first order 8 ms", r);
  const std::string text = run_record_text(run);
  EXPECT_NE(finding(run.findings, "actuator 1", "first_order"), nullptr) << text;
  EXPECT_EQ(finding(run.findings, "specimen 1", "inertia"), nullptr) << text;
  EXPECT_GE(r.declared, 0.05) << text;
  EXPECT_LE(r.identified, 0.01) << text;
  const IdentifiedRun written = identified_run(run, ".", std::filesystem::temp_directory_path());
  const config::Case* identified = study::case_named(written.study, kIdentifiedCaseName);
  ASSERT_NE(identified, nullptr);
  int masses = 0;
  for (const auto& stage : identified->delay()) masses += stage.has_inertia_force() ? 1 : 0;
  EXPECT_EQ(masses, 1) << identified->DebugString();
}

}  // namespace
}  // namespace rths::identify
