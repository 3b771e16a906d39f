#include "view/feed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <thread>
#include <vector>

#include "core/metrics.h"
#include "runtime/record/record_checks.h"

namespace rths::view {
namespace {

constexpr double kDt = 0.001;

runtime::RecordEntry header(int actuators = 1) {
  runtime::RecordEntry e;
  auto& h = *e.mutable_header();
  h.set_run_id("run-1");
  h.set_case_name("lag");
  h.set_clock("real_time");
  h.set_dt(kDt);
  h.set_dofs(1);
  h.set_actuators(actuators);
  h.add_link_node_ids(1);
  h.add_link_node_ids(2);
  return e;
}

// Command c = A sin(w t); measured m = A sin(w (t - lag)); k-th step.
runtime::RecordEntry step(std::int64_t k, double lag = 0.0, double amplitude = 0.01,
                          double hz = 2.0) {
  runtime::RecordEntry e;
  auto& s = *e.mutable_step();
  const double t = static_cast<double>(k) * kDt, w = 2 * std::numbers::pi * hz;
  s.set_step(k);
  s.set_time(t);
  s.add_displacement(0.5 * amplitude * std::sin(w * t));
  s.add_command(amplitude * std::sin(w * t));
  s.add_realised(amplitude * std::sin(w * (t - lag)));
  s.add_measured_force(1000.0 * static_cast<double>(k));
  for (int id : {1, 2}) {
    auto& l = *s.add_links();
    l.set_node_id(id);
    l.set_answered_step(k % 7 == 0 ? k - 1 : k);  // every 7th step on an older answer
    l.set_injected_lag(0.007);
    l.set_round_trip(0.0001 * static_cast<double>(id));
  }
  s.set_overrun(k % 100 == 5);
  s.set_lateness(k % 100 == 5 ? 0.002 : -0.0005);
  s.set_start_realtime_ns(1'000'000'000 + k * 1'000'000);
  return e;
}

runtime::RecordEntry event(std::int64_t at, const std::string& what) {
  runtime::RecordEntry e;
  e.mutable_event()->set_step(at);
  e.mutable_event()->set_what(what);
  return e;
}

TEST(Feed, KeepsEveryStrideThStepWithTheRecordsValuesInMillimetres) {
  Feed feed;  // 100 points per simulated second at dt = 1 ms: every 10th step
  feed.add(header());
  for (int k = 0; k < 1000; ++k) feed.add(step(k, 0.01));
  FeedCursor cursor;
  const auto j = feed.since(cursor);
  ASSERT_EQ(j["header"]["stride_steps"], 10);
  const auto& steps = j["samples"]["step"];
  ASSERT_EQ(steps.size(), 100u);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::int64_t k = steps[i];
    ASSERT_EQ(k, static_cast<std::int64_t>(10 * i));
    const auto s = step(k, 0.01).step();
    EXPECT_EQ(j["samples"]["command_mm"][0][i].get<double>(), s.command(0) * 1e3);
    EXPECT_EQ(j["samples"]["measured_mm"][0][i].get<double>(), s.realised(0) * 1e3);
    EXPECT_EQ(j["samples"]["force_N"][0][i].get<double>(), s.measured_force(0));
    EXPECT_EQ(j["samples"]["round_trip_ms"][1][i].get<double>(), s.links(1).round_trip() * 1e3);
    EXPECT_EQ(j["samples"]["injected_ms"][0][i].get<double>(), 7.0);
  }
  EXPECT_EQ(j["status"]["state"], "armed");
  EXPECT_EQ(j["status"]["steps"], 1000);
  EXPECT_EQ(j["status"]["overruns"], 10);
  EXPECT_EQ(j["status"]["late_feedback"], 143);  // k = 0, 7, ..., 994
  EXPECT_EQ(j["status"]["latest_step_realtime_ns"], 1'000'000'000 + 999 * 1'000'000LL);
}

TEST(Feed, ACursorGetsOnlyWhatIsNewAndALaggingReaderTheOldestKept) {
  FeedOptions options;
  options.history = 5;
  Feed feed(options);
  feed.add(header());
  FeedCursor live;
  for (int k = 0; k < 30; ++k) feed.add(step(k));
  const auto first = feed.since(live);
  EXPECT_TRUE(first.contains("header"));
  EXPECT_EQ(first["samples"]["step"], nlohmann::json({0, 10, 20}));
  for (int k = 30; k < 100; ++k) feed.add(step(k));
  const auto j = feed.since(live);
  EXPECT_FALSE(j.contains("header"));
  // 30..90 are new, but the ring keeps the newest 5 samples only.
  EXPECT_EQ(j["samples"]["step"], nlohmann::json({50, 60, 70, 80, 90}));
  FeedCursor fresh;
  EXPECT_EQ(feed.since(fresh)["samples"]["step"], nlohmann::json({50, 60, 70, 80, 90}));
  EXPECT_EQ(feed.since(live)["samples"]["step"].size(), 0u);
}

double final_ti(double lag) {
  Feed feed;
  feed.add(header());
  for (int k = 0; k <= 2000; ++k) feed.add(step(k, lag));  // 4 cycles of 2 Hz
  FeedCursor cursor;
  return feed.since(cursor)["samples"]["ti_mm2"][0].back().get<double>();
}

TEST(Feed, TrackingIndicatorGrowsWithLagFallsWithLeadAndStaysNearZeroWhenTracking) {
  // Per cycle: A = integral of m dc = -pi a^2 sin(w lag) and TA = -A, so TI = pi a^2 sin(w lag)
  // per cycle (mm^2); 4 cycles.
  const double a = 10.0, w = 2 * std::numbers::pi * 2.0;
  const double expected = 4 * std::numbers::pi * a * a * std::sin(w * 0.01);
  EXPECT_NEAR(final_ti(0.01), expected, 0.02 * expected);
  EXPECT_NEAR(final_ti(-0.01), -expected, 0.02 * expected);
  EXPECT_NEAR(final_ti(0.0), 0.0, 1e-9);
}

TEST(Feed, SpectrumOfTheErrorPeaksAtItsFrequencyWithItsAmplitudeOnALogFrequencyGrid) {
  Feed feed;
  feed.add(header());
  FeedCursor cursor;
  const auto h = feed.since(cursor)["header"];
  // The window: the largest power of two of steps within 4 s; 20 frequencies per decade from
  // 1 / window up to 100 Hz.
  ASSERT_EQ(h["spectrum_window_steps"], 2048);
  const auto& hz = h["spectrum_hz"];
  const double lowest = 1.0 / (2048 * kDt);
  ASSERT_DOUBLE_EQ(hz[0].get<double>(), lowest);
  for (std::size_t i = 1; i < hz.size(); ++i)
    EXPECT_NEAR(hz[i].get<double>() / hz[i - 1].get<double>(), std::pow(10.0, 0.05), 1e-12);
  EXPECT_LE(hz.back().get<double>(), 100.0);
  EXPECT_GT(hz.back().get<double>() * std::pow(10.0, 0.05), 100.0);
  // command 0, measured = -2 mm sin(2 pi f t) at the grid's frequency nearest 5 Hz: error 2 mm.
  std::size_t at = 0;
  for (std::size_t i = 0; i < hz.size(); ++i)
    if (std::abs(hz[i].get<double>() - 5.0) < std::abs(hz[at].get<double>() - 5.0)) at = i;
  const double f = hz[at];
  for (int k = 0; k < 5000; ++k) {
    auto e = step(k);
    e.mutable_step()->set_command(0, 0.0);
    e.mutable_step()->set_realised(
        0, -0.002 * std::sin(2 * std::numbers::pi * f * static_cast<double>(k) * kDt));
    feed.add(e);
  }
  const auto j = feed.since(cursor);
  ASSERT_FALSE(j["spectra"].empty());
  const auto& amp = j["spectra"].back()["amplitude_mm"][0];
  ASSERT_EQ(amp.size(), hz.size());
  std::size_t peak = 0;
  for (std::size_t i = 0; i < amp.size(); ++i)
    if (amp[i].get<double>() > amp[peak].get<double>()) peak = i;
  EXPECT_EQ(peak, at);
  // Not on an integer bin: the mirror image at -f leaks a little through the Hann window.
  EXPECT_NEAR(amp[peak].get<double>(), 2.0, 2e-3);
  EXPECT_LT(amp[at + 6].get<double>(), 0.02);  // an octave away
}

TEST(Feed, AHoldEventAndTheFooterSetTheFailSafeState) {
  Feed feed;
  feed.add(header());
  feed.add(step(0));
  feed.add(event(0, "all 2 nodes ready"));
  FeedCursor cursor;
  EXPECT_EQ(feed.since(cursor)["status"]["state"], "armed");
  feed.add(event(12, "HOLD sent to the actuator emulators: stopped from the view"));
  auto j = feed.since(cursor);
  EXPECT_EQ(j["status"]["state"], "HOLD");
  EXPECT_EQ(j["status"]["reason"], "HOLD sent to the actuator emulators: stopped from the view");
  EXPECT_EQ(j["events"].size(), 1u);
  EXPECT_FALSE(feed.finished());
  runtime::RecordEntry footer;
  footer.mutable_footer()->set_ok(false);
  footer.mutable_footer()->set_status("node 2 (actuator emulator) gave no answer");
  footer.mutable_footer()->set_failed_node("node 2 (actuator emulator)");
  feed.add(footer);
  j = feed.since(cursor);
  EXPECT_EQ(j["status"]["state"], "stopped");
  EXPECT_EQ(j["status"]["node"], "node 2 (actuator emulator)");
  EXPECT_TRUE(j["status"]["finished"]);
  EXPECT_TRUE(feed.finished());
}

// A controller link's diagnostic channels are named in the header (from its layout) and drawn
// from each kept step's link sample, unchanged.
TEST(Feed, AControllersDiagnosticChannelsAreNamedAndSampled) {
  Feed feed;
  runtime::RecordEntry h = header();
  auto& node = *h.mutable_header()->mutable_study()->mutable_deployment()->add_nodes();
  node.set_id(2);
  node.set_kind(config::NodeSpec::CONTROLLER);
  for (const char* name : {"task_time", "supply_pressure"}) {
    auto& f = *node.mutable_controller()->mutable_feedback()->add_fields();
    f.set_name(name);
    f.set_role(config::FrameField::DIAGNOSTIC);
  }
  feed.add(h);
  for (std::int64_t k = 0; k < 30; ++k) {  // every 10th step kept: 0, 10, 20
    runtime::RecordEntry e = step(k);
    e.mutable_step()->mutable_links(1)->add_controller_diagnostics(0.0004 + 1e-5 * k);
    e.mutable_step()->mutable_links(1)->add_controller_diagnostics(2.1e7);
    feed.add(e);
  }
  FeedCursor cursor;
  const auto j = feed.since(cursor);
  ASSERT_EQ(j["header"]["diagnostics"].size(), 2u);  // per link: none on node 1
  EXPECT_TRUE(j["header"]["diagnostics"][0].empty());
  EXPECT_EQ(j["header"]["diagnostics"][1][1], "supply_pressure");
  const auto& d = j["samples"]["diagnostics"];
  ASSERT_EQ(d[1].size(), 2u);
  ASSERT_EQ(d[1][0].size(), 3u);
  EXPECT_DOUBLE_EQ(d[1][0][2].get<double>(), 0.0004 + 1e-5 * 20);
  EXPECT_DOUBLE_EQ(d[1][1][0].get<double>(), 2.1e7);
}

// A controller node's hold reaches the page from the footer: its link line and each HOLD frame,
// answer and STOP, in order.
TEST(Feed, AControllersHoldIsShownFrameByFrame) {
  Feed feed;
  feed.add(header());
  feed.add(step(0));
  runtime::RecordEntry footer;
  footer.mutable_footer()->set_ok(false);
  footer.mutable_footer()->set_status("controller: implausible measurement");
  runtime::NodeRejects& node = *footer.mutable_footer()->add_node_rejects();
  node.set_node_id(2);
  node.set_label("node 2 (controller)");
  runtime::ControllerReport& r = *node.mutable_controller();
  r.set_hold_frames(1);
  r.set_held_after(0.003);
  for (const auto kind :
       {runtime::HoldEntry::SENT_HOLD, runtime::HoldEntry::ANSWER, runtime::HoldEntry::SENT_STOP}) {
    runtime::HoldEntry* e = r.add_hold_log();
    e->set_kind(kind);
    e->add_position(0.0021);
    e->set_verdict(kind == runtime::HoldEntry::ANSWER ? "held" : "");
  }
  feed.add(footer);
  FeedCursor cursor;
  const auto j = feed.since(cursor)["status"]["controllers"];
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["label"], "node 2 (controller)");
  EXPECT_NE(j[0]["link"].get<std::string>().find("1 HOLD frames, held after 3.000 ms"),
            std::string::npos)
      << j[0]["link"];
  ASSERT_EQ(j[0]["hold"]["entries"].size(), 3u);
  EXPECT_EQ(j[0]["hold"]["entries"][1]["verdict"], "held");
  EXPECT_EQ(j[0]["hold"]["entries"][2]["kind"], "sent STOP");
}

// The badge is the one real-time verdict on the record's rows (the header's deployment: the
// default 0.001 tolerance and 3-step answer window): a run whose rows hold a streak of 5 overruns
// is `failed` with the verdict as its reason even when its footer says ok (an older coordinator's
// record); a footer naming deadline misses is `failed` too; rows within the rule stay
// `completed`, their badge a warning naming the overruns (view/verdict.h); a lockstep record is
// never judged on deadlines.
TEST(Feed, ARealTimeRunThatFailedItsVerdictIsShownFailedNeverCompleted) {
  const auto finished = [](const std::string& clock, int streak, bool ok,
                           const std::string& status) {
    Feed feed;
    runtime::RecordEntry h = header();
    h.mutable_header()->set_clock(clock);
    feed.add(h);
    for (int k = 0; k < 10001; ++k) {
      runtime::RecordEntry e = step(k);
      e.mutable_step()->set_overrun(k >= 100 && k < 100 + streak);
      feed.add(e);
    }
    runtime::RecordEntry footer;
    footer.mutable_footer()->set_ok(ok);
    footer.mutable_footer()->set_status(status);
    feed.add(footer);
    FeedCursor cursor;
    return feed.since(cursor)["status"];
  };
  auto s = finished("real_time", 5, true, "completed");
  EXPECT_EQ(s["state"], "failed");
  EXPECT_EQ(s["verdict"]["badge"], "completed with deadline misses");
  EXPECT_EQ(s["verdict"]["level"], "failed");
  EXPECT_EQ(s["reason"],
            "completed with deadline misses: 5 steps in a row overran, more than the fail-safe's "
            "window of 3 (5 overruns in 10000 steps, 0.050000 %): the integrator used stale "
            "forces that long, the response is not a real-time test's");
  s = finished("real_time", 3, true, "completed");
  EXPECT_EQ(s["state"], "completed") << s["reason"];
  EXPECT_EQ(s["verdict"]["badge"], "completed with 3 overruns");
  EXPECT_EQ(s["verdict"]["level"], "warning");
  s = finished("real_time", 0, false, "completed with deadline misses: the servo loop ...");
  EXPECT_EQ(s["state"], "failed");
  EXPECT_EQ(s["reason"], "completed with deadline misses: the servo loop ...");
  EXPECT_EQ(finished("lockstep", 5, true, "completed")["state"], "completed");
  EXPECT_EQ(finished("lockstep", 5, true, "completed")["verdict"]["level"], "ok");
}

// What the page receives: the JSON as written (NaN, no prediction, becomes null).
nlohmann::json as_sent(const nlohmann::json& j) { return nlohmann::json::parse(j.dump()); }

// The predicted displacement of one DOF at step k: 1 mm * sin(k / 50) (m).
double predicted_u(std::int64_t k) { return 0.001 * std::sin(static_cast<double>(k) / 50.0); }

core::SimulationResult prediction(int steps) {
  core::SimulationResult p;
  p.dt = kDt;
  p.displacement.resize(steps, 1);
  for (int k = 0; k < steps; ++k) p.displacement(k, 0) = predicted_u(k);
  return p;
}

// The record's displacement is the prediction plus `offset` (m) from step `from` on.
runtime::RecordEntry step_near(std::int64_t k, double offset, std::int64_t from) {
  runtime::RecordEntry e = step(k);
  e.mutable_step()->set_displacement(0, predicted_u(k) + (k >= from ? offset : 0.0));
  return e;
}

void expect_prediction_samples(const nlohmann::json& samples, const core::SimulationResult& p,
                               std::size_t predicted_steps) {
  const auto& steps = samples["step"];
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::int64_t k = steps[i];
    const auto& predicted = samples["predicted_u_mm"][0][i];
    if (static_cast<std::size_t>(k) >= predicted_steps) {
      EXPECT_TRUE(predicted.is_null()) << "step " << k;
      EXPECT_TRUE(samples["difference_mm"][0][i].is_null()) << "step " << k;
      continue;
    }
    EXPECT_EQ(predicted.get<double>(), p.displacement(k, 0) * 1e3) << "step " << k;
    EXPECT_EQ(samples["difference_mm"][0][i].get<double>(),
              samples["u_mm"][0][i].get<double>() - predicted.get<double>());
  }
}

TEST(Feed, DrawsTheResponseAgainstThePredictionAtTheSamplesStepsWithItsRunningDifference) {
  const core::SimulationResult p = prediction(1000);
  Feed feed;
  feed.set_prediction(p);  // as the coordinator does: before the header
  feed.add(header());
  for (int k = 0; k < 1200; ++k) feed.add(step_near(k, 0.0005, 500));  // 0.5 mm from 500 on
  FeedCursor cursor;
  const auto j = as_sent(feed.since(cursor));
  ASSERT_EQ(j["samples"]["step"].size(), 120u);
  EXPECT_EQ(j["header"]["dof_labels"], nlohmann::json({"floor 1"}));
  expect_prediction_samples(j["samples"], p, 1000);  // none past the prediction's 1000 steps
  EXPECT_NEAR(j["samples"]["difference_mm"][0][10].get<double>(), 0.0, 1e-12);  // step 100
  EXPECT_NEAR(j["samples"]["difference_mm"][0][60].get<double>(), 0.5, 1e-9);   // step 600
  const auto& stats = j["status"]["prediction"];
  EXPECT_EQ(stats["compared_samples"], 100);  // steps 0, 10, ..., 990
  EXPECT_NEAR(stats["max_abs_difference_mm"][0].get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(stats["rms_difference_mm"][0].get<double>(), 0.5 * std::sqrt(0.5), 1e-9);
  // E_peak and E_rms against the prediction over the same samples, as core/metrics.h defines
  // them for `rths run`.
  std::vector<double> measured, predicted;
  for (int k = 0; k < 1000; k += 10) {
    predicted.push_back(p.displacement(k, 0) * 1e3);
    measured.push_back(predicted.back() + (k >= 500 ? 0.5 : 0.0));
  }
  EXPECT_NEAR(stats["peak_error_pct"][0].get<double>(),
              core::relative_peak_error_pct(predicted, measured), 1e-9);
  EXPECT_NEAR(stats["rms_error_pct"][0].get<double>(),
              core::relative_rms_error_pct(predicted, measured), 1e-9);
  EXPECT_GT(stats["rms_error_pct"][0].get<double>(), 0.0);
}

TEST(Feed, APredictionGivenAfterTheStepsFillsTheKeptSamples) {
  const core::SimulationResult p = prediction(2000);
  Feed feed;
  feed.add(header());
  for (int k = 0; k < 1000; ++k) feed.add(step_near(k, 0.0, 0));
  FeedCursor before;
  EXPECT_FALSE(feed.since(before)["status"].contains("prediction"));
  feed.set_prediction(p);  // as `rths view` may: after the record's steps
  FeedCursor after;
  const auto j = as_sent(feed.since(after));
  expect_prediction_samples(j["samples"], p, 2000);
  EXPECT_EQ(j["status"]["prediction"]["compared_samples"], 100);
  EXPECT_EQ(j["status"]["prediction"]["max_abs_difference_mm"][0].get<double>(), 0.0);
}

// A large model's record keeps the DOFs its recorders name (RunHeader.recorded_dofs): each column
// is labelled and compared with the prediction of its own DOF, not of the column's position.
TEST(Feed, ARecordOfChosenDofsIsLabelledAndPredictedByThoseDofs) {
  core::SimulationResult p;
  p.dt = kDt;
  p.displacement = Eigen::MatrixXd::Zero(100, 500);
  p.displacement.col(4).setConstant(0.004);    // DOF 5: 4 mm
  p.displacement.col(249).setConstant(0.249);  // DOF 250: 249 mm
  Feed feed;
  feed.set_prediction(p);
  runtime::RecordEntry h = header();
  h.mutable_header()->set_dofs(500);
  h.mutable_header()->add_recorded_dofs(4);
  h.mutable_header()->add_recorded_dofs(249);
  feed.add(h);
  for (int k = 0; k < 100; ++k) {
    runtime::RecordEntry s = step(k);
    s.mutable_step()->set_displacement(0, 0.004);
    s.mutable_step()->add_displacement(0.250);  // 1 mm off its DOF's prediction
    feed.add(s);
  }
  FeedCursor cursor;
  const auto j = as_sent(feed.since(cursor));
  EXPECT_EQ(j["header"]["dof_labels"], nlohmann::json({"floor 5", "floor 250"}));
  ASSERT_EQ(j["samples"]["predicted_u_mm"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["samples"]["predicted_u_mm"][1][3].get<double>(), 249.0);
  EXPECT_NEAR(j["samples"]["difference_mm"][0][3].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(j["samples"]["difference_mm"][1][3].get<double>(), 1.0, 1e-9);
}

// A large model's prediction keeps only the recorded DOFs (view/context.h predict_case): each
// record column is looked up by its DOF among them, and a DOF it did not keep has none.
TEST(Feed, APredictionOfTheRecordedDofsIsLookedUpByDof) {
  core::SimulationResult p;
  p.dt = kDt;
  p.displacement = Eigen::MatrixXd::Zero(100, 2);
  p.displacement.col(0).setConstant(0.004);  // DOF 5: 4 mm
  p.displacement.col(1).setConstant(0.249);  // DOF 250: 249 mm
  p.dofs = {4, 249};
  Feed feed;
  feed.set_prediction(p);
  runtime::RecordEntry h = header();
  h.mutable_header()->set_dofs(500);
  for (const int dof : {4, 249, 299}) h.mutable_header()->add_recorded_dofs(dof);
  feed.add(h);
  for (int k = 0; k < 100; ++k) {
    runtime::RecordEntry s = step(k);
    s.mutable_step()->set_displacement(0, 0.004);
    s.mutable_step()->add_displacement(0.250);
    s.mutable_step()->add_displacement(0.0);
    feed.add(s);
  }
  FeedCursor cursor;
  const auto j = as_sent(feed.since(cursor));
  ASSERT_EQ(j["samples"]["predicted_u_mm"].size(), 3u);
  EXPECT_DOUBLE_EQ(j["samples"]["predicted_u_mm"][0][3].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(j["samples"]["predicted_u_mm"][1][3].get<double>(), 249.0);
  EXPECT_NEAR(j["samples"]["difference_mm"][1][3].get<double>(), 1.0, 1e-9);
  EXPECT_TRUE(j["samples"]["predicted_u_mm"][2][3].is_null());
}

// A crafted header sizes nothing: the page says which field it refused (and its value), and no
// step is drawn.
TEST(Feed, AHeaderBeyondARecordsLimitsIsRefusedNamingTheField) {
  struct Crafted {
    int dofs;
    std::vector<int> recorded;
    std::string named;
  };
  for (const Crafted& c : std::vector<Crafted>{
           {runtime::kMaxRecordDofs + 1, {}, "run header: dofs 10001 outside [0, 10000]"},
           {500, {249, 4}, "run header: recorded_dofs[1] 4 is not a DOF of 0..499"},
           {500, {4, 500}, "run header: recorded_dofs[1] 500 is not a DOF of 0..499"}}) {
    FeedOptions options;
    options.history = 100;  // a refused header must size nothing; so little if it did
    Feed feed(options);
    runtime::RecordEntry h = header();
    h.mutable_header()->set_dofs(c.dofs);
    for (const int dof : c.recorded) h.mutable_header()->add_recorded_dofs(dof);
    feed.add(h);
    feed.add(step(0));
    FeedCursor cursor;
    const auto j = as_sent(feed.since(cursor));
    EXPECT_EQ(j["status"]["state"], "refused") << c.named;
    EXPECT_EQ(j["status"]["reason"].get<std::string>().rfind(c.named, 0), 0u)
        << j["status"]["reason"];
    EXPECT_FALSE(j.contains("header"));
    EXPECT_EQ(j["status"]["steps"], 0);
  }
  Feed feed;
  runtime::RecordEntry h = header();
  for (int l = 0; l < runtime::kMaxRecordDofs; ++l) h.mutable_header()->add_link_node_ids(l);
  feed.add(h);  // 10,002 links: each would size rings of the feed's whole history
  FeedCursor cursor;
  const auto j = as_sent(feed.since(cursor));
  EXPECT_EQ(j["status"]["state"], "refused");
  EXPECT_EQ(j["status"]["reason"],
            "run header: link_node_ids holds 10002 links, outside [0, 10000]");
}

TEST(Feed, WithoutAPredictionTheResponseIsDrawnAlone) {
  Feed feed;
  feed.add(header());
  for (int k = 0; k < 100; ++k) feed.add(step(k));
  FeedCursor cursor;
  const auto j = as_sent(feed.since(cursor));
  ASSERT_EQ(j["samples"]["u_mm"][0].size(), 10u);
  EXPECT_EQ(j["samples"]["u_mm"][0][3].get<double>(), step(30).step().displacement(0) * 1e3);
  EXPECT_TRUE(j["samples"]["predicted_u_mm"][0][3].is_null());
  EXPECT_FALSE(j["status"].contains("prediction"));
}

std::string frame(const runtime::RecordEntry& e) {
  std::string out;
  runtime::append_record_frame(e, out);
  return out;
}

TEST(Feed, ObservesTheWritersBytesAndCountsWhatItCannotRead) {
  Feed feed;
  feed.on_entry(frame(header()));
  feed.on_entry(frame(step(0)));
  feed.on_entry(std::string(runtime::kRecordFrameHeaderBytes, '\0') + "\xff\xff garbage");
  feed.on_entry(std::string_view("\xff", 1));
  EXPECT_EQ(feed.steps_seen(), 1u);
  EXPECT_EQ(feed.unreadable_entries(), 2u);
}

TEST(Feed, WaitChangeWakesOnANewEntry) {
  Feed feed;
  const auto version = feed.version();
  std::thread writer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    feed.add(header());
  });
  EXPECT_NE(feed.wait_change(version, std::chrono::seconds(10)), version);
  writer.join();
}

}  // namespace
}  // namespace rths::view
