// The fault drills through the controller written from docs/controller.md alone
// (tests/support/doc_controller.h, harness in doc_controller_harness.h): each fault the issue
// lists, switched on at a chosen frame, must HOLD naming its cause, fail the run with its record
// complete, apply nothing past the fault, and bring the rig to rest with repeated HOLD frames at
// the last measured position before STOP. Processes over Cyclone DDS on loopback, the controller a
// thread of this test; the shared DDS domain, each drill on topics of its own, and UDP ports of
// its own (doc_controller_test.cpp lists the file pair's).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "../runtime/test_support.h"
#include "doc_controller_harness.h"
#include "tests/support/dds_scope.h"
#include "tests/support/real_time_run.h"
#include "tests/support/run_command_line.h"

namespace rths {
namespace {

using namespace doc_test;

// ------------------------------------------------------------------------------------------------
// c. Fault drills. Each: the run fails (exit != 0), the footer (the record is complete) names the
// cause and the link report counts it under the docs' name, nothing recorded applied the faulty
// value, and the controller saw the docs' HOLD sequence: repeated HOLD frames (status 1) carrying
// the last measured position (a rebooted controller's: where it restarted), then STOP only after
// it answered held (or after hold_time_ms when it never does); the record's footer holds the
// whole hold (every HOLD frame, the answers, the STOP).
struct Drill {
  std::string name;
  int node_port = 0, peer_port = 0;
  DocFault fault = DocFault::kNone;
  double fault_value = 0.0;
  bool real_time = false;
  std::string link_extra;          // inside the link
  std::vector<std::string> cause;  // every one of these in the footer's status
  // The link report's count for the cause (docs' "counted as").
  std::uint64_t (runtime::ControllerReport::*count)() const = nullptr;
  bool controller_answers_hold = true;  // false: silent, STOP after hold_time_ms
  double hold_time_ms = 500;
  bool default_checks = false;  // true: none of the plausibility bounds the docs ask a lab to set
  std::string motion;           // inside the study's motion block (a scale)
};

// Reference peaks of the drills' run: where the fault goes and the plausibility bounds. A stuck
// displacement leaves its target fastest at the step of peak velocity; a rebooted controller's
// drift jumps farthest (to 0) at the step of peak displacement.
struct Peaks {
  std::uint32_t velocity_frame = 0, displacement_frame = 0;
  double peak_velocity = 0, peak_displacement = 0;
};
Peaks lockstep_peaks(const std::string& text) {
  const core::SimulationResult reference = test::reference_result(text, "reference");
  Peaks p;
  for (Eigen::Index k = 1; k < reference.velocity.rows(); ++k) {
    const double v = std::abs(reference.velocity(k, 0));
    const double u = std::abs(reference.displacement(k, 0));
    if (v > p.peak_velocity) {
      p.peak_velocity = v;
      p.velocity_frame = static_cast<std::uint32_t>(k);
    }
    if (u > p.peak_displacement) {
      p.peak_displacement = u;
      p.displacement_frame = static_cast<std::uint32_t>(k);
    }
  }
  return p;
}

// The plausibility bounds the docs ask a lab to set: the measured drift's rate at 4 x the peak
// velocity, the force's at 4 x the specimen's stiffness x the peak velocity, the tracking error at
// a quarter of the peak drift for 3 answers (the lag-free plant tracks within f32 resolution; a
// fixed bound in mm would never be reached by this short motion's sub-mm drifts).
std::string plausibility(const Peaks& p) {
  return "max_measured_rate: " + std::to_string(4 * p.peak_velocity) +
         " max_force_rate: " + std::to_string(4 * kSpecimenStiffness * p.peak_velocity) +
         " max_tracking_error: " + std::to_string(0.25 * p.peak_displacement) +
         " tracking_error_steps: 3";
}

void run_drill(Drill drill) {
  const double dt = drill.real_time ? kRealTimeDt : 0.001;
  const double duration = drill.real_time ? 1.5 : 1.0;
  const std::string probe =
      study_text(duration, dt, drill.node_port, drill.peer_port, "", "", drill.motion);
  const Peaks peaks = lockstep_peaks(probe);
  ASSERT_GT(peaks.velocity_frame, 50u);
  ASSERT_GT(peaks.displacement_frame, 50u);
  const std::uint32_t fault_frame = drill.real_time                    ? 700
                                    : drill.fault == DocFault::kReboot ? peaks.displacement_frame
                                                                       : peaks.velocity_frame;
  const std::string link = "reply_timeout_ms: " + std::string(drill.real_time ? "8" : "200") +
                           " hold_time_ms: " + std::to_string(drill.hold_time_ms) + " " +
                           (drill.default_checks ? "" : plausibility(peaks)) + " " +
                           drill.link_extra;
  const std::string text =
      study_text(duration, dt, drill.node_port, drill.peer_port, link,
                 drill.real_time ? real_time_deployment() : std::string(""), drill.motion);
  DocControllerOptions options = controller_options(drill.peer_port, drill.node_port, dt);
  options.answer_lag = drill.real_time ? 0.002 : 0.0;
  options.fault = drill.fault;
  options.fault_frame = fault_frame;
  options.fault_value = drill.fault_value;
  options.held_after_hold_frames = 3;
  DocController controller(options);
  const auto witnessed =
      test::launch_witnessed(drill.name, text, "reference", test::scope_dds_to_this_test());
  const auto& run = witnessed.run;
  // The node's STOP frame follows the hold; give it time to land before the controller stops.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  controller.stop();
  const std::string coordinator_log = test::read_file(run.launch.coordinator_log);
  const std::string node_log = test::read_file(run.dir / "node_2.log");
  SCOPED_TRACE(drill.name + " at frame " + std::to_string(fault_frame) + ", peak drift " +
               std::to_string(peaks.peak_displacement * 1e3) + " mm");

  EXPECT_NE(run.launch.coordinator_exit, 0) << coordinator_log;
  const runtime::RunFooter* footer = run.record.footer();
  ASSERT_NE(footer, nullptr) << "the record is complete: it has a footer";
  EXPECT_FALSE(footer->ok());
  // A real-time drill stopped by a stall of this machine before its fault came is not judged.
  const bool named = std::all_of(drill.cause.begin(), drill.cause.end(), [&](const auto& word) {
    return footer->status().find(word) != std::string::npos;
  });
  if (const auto burned = test::loop_cpu_over_bound(coordinator_log)) FAIL() << *burned;
  if (!named)
    if (const auto why =
            test::machine_stalled(footer->status(), *run.record.header(), witnessed.machine))
      GTEST_SKIP() << *why;
  for (const auto& word : drill.cause)
    EXPECT_NE(footer->status().find(word), std::string::npos)
        << "status: " << footer->status() << "\nnode log:\n"
        << node_log;
  const runtime::NodeRejects* rejects = node2(run.record);
  ASSERT_NE(rejects, nullptr);
  if (drill.count)
    EXPECT_GE((rejects->controller().*drill.count)(), 1u) << rejects->controller().DebugString();

  // Nothing recorded applied a faulty answer. Lockstep: step k is frame k's answer; the answers
  // the node must refuse are those at and after the fault (for the tracking error, the docs allow
  // tracking_error_steps - 1 answers beyond the bound before the HOLD: counted below).
  const auto sent = controller.sent();
  std::map<std::uint32_t, test::SentAnswer> answers;
  for (const auto& a : sent)
    if (!answers.count(a.counter)) answers[a.counter] = a;
  const auto steps = run.record.steps();
  int beyond_tracking = 0;
  for (const runtime::StepRecord* s : steps) {
    const double u = s->realised(0), f = s->measured_force(0);
    EXPECT_TRUE(std::isfinite(u) && std::isfinite(f)) << "step " << s->step();
    EXPECT_LE(std::abs(u), 1.0) << "step " << s->step() << ": beyond twice max_displacement";
    // The linear specimen: every applied answer has f = k u (to f32 resolution in mm and kN);
    // a jumped force or a rebooted controller's 0 N at a moving drift breaks it.
    EXPECT_NEAR(f, kSpecimenStiffness * u, 1e-5 * std::max(1.0, std::abs(f)))
        << "step " << s->step();
    if (std::abs(u - s->command(0)) > 0.002 && s->step() > 0) ++beyond_tracking;
    if (drill.fault == DocFault::kReboot && s->step() >= fault_frame && s->step() > 0)
      EXPECT_FALSE(u == 0.0 && f == 0.0) << "step " << s->step() << " applied the rebooted state";
  }
  EXPECT_LT(beyond_tracking, 3) << "answers beyond max_tracking_error applied";
  if (!drill.real_time && drill.fault != DocFault::kStuckDisplacement)
    EXPECT_LE(steps.size(), fault_frame + 1u) << "nothing recorded past the faulty step";

  // The HOLD sequence at the controller.
  const auto frames = controller.received();
  expect_counters_and_padding(frames);
  std::size_t first_hold = frames.size();
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (frames[i].status == 1) {
      first_hold = i;
      break;
    }
  ASSERT_LT(first_hold, frames.size()) << "no HOLD frame reached the controller";
  // The last measured position: the newest answer the node accepted before the HOLD. Answers at
  // and after the fault are refused, except the stuck drift's first ones, which carry the value
  // it froze at (the answer before the fault's), so in every drill it is the newest answer sent
  // to a run frame before the fault frame.
  double last_measured = 0;
  for (const auto& a : sent)
    if (a.counter < fault_frame && a.status == 0) last_measured = a.displacement;
  // A rebooted controller is held where it then is (0, its plant restarted), never sent back to
  // where the rig was before the reboot.
  if (drill.fault == DocFault::kReboot) last_measured = 0.0;
  int holds = 0;
  std::int64_t first_hold_ns = frames[first_hold].receive_ns, stop_ns = -1;
  for (std::size_t i = first_hold; i < frames.size(); ++i) {
    const auto& f = frames[i];
    EXPECT_NE(f.status, 0) << "a run frame after the first HOLD frame (counter " << f.counter
                           << ")";
    if (f.status == 1) {
      ++holds;
      EXPECT_NEAR(f.target, last_measured, 1e-9) << "HOLD frame " << f.counter;
    }
    if (f.status == 2 && stop_ns < 0) stop_ns = f.receive_ns;
  }
  EXPECT_GE(holds, 2) << "HOLD frames repeat every dt until the controller says held";
  ASSERT_GE(stop_ns, 0) << "no STOP frame reached the controller";
  // The hold on the record: as many HOLD frames as the controller saw, the last frame sent the
  // STOP (what the controller still answered after it is logged behind it, never a frame sent).
  const runtime::ControllerReport& report = rejects->controller();
  int logged_holds = 0, last_sent = -1;
  for (int i = 0; i < report.hold_log_size(); ++i) {
    const runtime::HoldEntry& e = report.hold_log(i);
    if (e.kind() == runtime::HoldEntry::SENT_HOLD) ++logged_holds;
    if (e.kind() != runtime::HoldEntry::ANSWER) last_sent = i;
  }
  EXPECT_EQ(logged_holds, holds) << report.DebugString();
  ASSERT_GE(last_sent, 0);
  EXPECT_EQ(report.hold_log(last_sent).kind(), runtime::HoldEntry::SENT_STOP);
  if (drill.controller_answers_hold) {
    std::int64_t held_ns = -1;
    for (const auto& a : sent)
      if (a.status == 1 && held_ns < 0) held_ns = a.send_ns;
    ASSERT_GE(held_ns, 0) << "the controller never answered held";
    EXPECT_GT(stop_ns, held_ns) << "STOP only after the controller answered held";
    EXPECT_GE(holds, 3) << "the controller says held at its third HOLD frame";
  } else {
    EXPECT_GE(static_cast<double>(stop_ns - first_hold_ns) * 1e-6, drill.hold_time_ms - 1.0)
        << "STOP before hold_time_ms with a controller that never said held";
  }
}

TEST_F(DocControllerTest, DrillSilentControllerRealTime) {
  Drill d;
  d.name = "doc_drill_silent";
  d.node_port = 47310, d.peer_port = 47311;
  d.fault = DocFault::kSilent;
  d.real_time = true;
  d.cause = {"did not answer"};
  d.count = &runtime::ControllerReport::lost;
  d.controller_answers_hold = false;
  d.hold_time_ms = 100;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillBadStatus) {
  Drill d;
  d.name = "doc_drill_bad_status";
  d.node_port = 47312, d.peer_port = 47313;
  d.fault = DocFault::kBadStatus;
  d.fault_value = 7;
  d.cause = {"status 7"};
  d.count = &runtime::ControllerReport::bad_status;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillNanForce) {
  Drill d;
  d.name = "doc_drill_nan";
  d.node_port = 47314, d.peer_port = 47315;
  d.fault = DocFault::kNanForce;
  d.cause = {"force"};
  d.count = &runtime::ControllerReport::non_finite;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillWrongEcho) {
  Drill d;
  d.name = "doc_drill_wrong_echo";
  d.node_port = 47316, d.peer_port = 47317;
  d.fault = DocFault::kWrongEcho;
  d.cause = {"counter"};
  d.count = &runtime::ControllerReport::unexpected_counter;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillWrongSize) {
  Drill d;
  d.name = "doc_drill_wrong_size";
  d.node_port = 47318, d.peer_port = 47319;
  d.fault = DocFault::kWrongSize;
  d.cause = {"28"};  // the frame's size, against the feedback frame's 24 bytes
  d.count = &runtime::ControllerReport::wrong_size;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillOutOfRange) {
  Drill d;
  d.name = "doc_drill_out_of_range";
  d.node_port = 47320, d.peer_port = 47321;
  d.fault = DocFault::kOutOfRange;
  d.fault_value = 1.5;  // m: beyond twice limits.max_displacement (0.5 m)
  d.cause = {"1.5"};
  d.count = &runtime::ControllerReport::out_of_range;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillCounterReset) {
  Drill d;
  d.name = "doc_drill_counter_reset";
  d.node_port = 47322, d.peer_port = 47323;
  d.fault = DocFault::kCounterReset;
  d.cause = {"counter"};
  d.count = &runtime::ControllerReport::repeated_counter;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillRebootWithCorrectEchoButStateLost) {
  Drill d;
  d.name = "doc_drill_reboot";
  d.node_port = 47324, d.peer_port = 47325;
  d.fault = DocFault::kReboot;
  d.cause = {"max_measured_rate"};  // the first check the docs list for a drift's jump
  d.count = &runtime::ControllerReport::implausible;
  run_drill(d);
}

// The same reboot with the node's default checks only (the measured jump, on by default), at a
// drift of a few mm (the motion scaled 50 times: 2 mm at its peak): held, and held where the
// rebooted rig is.
TEST_F(DocControllerTest, DrillRebootCaughtByTheDefaultChecks) {
  Drill d;
  d.motion = "scale: 50";
  d.name = "doc_drill_reboot_defaults";
  d.node_port = 47332, d.peer_port = 47333;
  d.fault = DocFault::kReboot;
  d.cause = {"jumped", "a restarted controller"};
  d.count = &runtime::ControllerReport::implausible;
  d.default_checks = true;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillForceJump) {
  Drill d;
  d.name = "doc_drill_force_jump";
  d.node_port = 47326, d.peer_port = 47327;
  d.fault = DocFault::kForceJump;
  d.fault_value = 5000;  // N in one step: 5e6 N/s against a bound of a few 1e4 N/s
  d.cause = {"max_force_rate"};
  d.count = &runtime::ControllerReport::implausible;
  run_drill(d);
}

TEST_F(DocControllerTest, DrillTrackingErrorPastItsBound) {
  Drill d;
  d.name = "doc_drill_tracking";
  d.node_port = 47328, d.peer_port = 47329;
  d.fault = DocFault::kStuckDisplacement;
  d.cause = {"max_tracking_error"};
  d.count = &runtime::ControllerReport::implausible;
  run_drill(d);
}

}  // namespace
}  // namespace rths
