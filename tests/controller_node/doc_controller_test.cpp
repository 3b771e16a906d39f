// rths's CONTROLLER node driven through a lab's controller written from docs/controller.md alone
// (tests/support/doc_controller.h): big-endian F32 frames in mm and kN with padding, a linear
// specimen behind a lag, answers pipelined after a lag. What each test checks is what the docs
// (controller.md, configuration.md ControllerLink/FrameLayout/FrameField/Deployment/
// SafetyLimits, faults.md) promise; where rths does otherwise the test fails rather than bend.
// The coordinator and the node are processes over Cyclone DDS on loopback (test::launch), the
// controller a thread of this test. The shared DDS domain, each test on topics of its own; UDP
// ports 47300-47399.
//
// RTHS_DOC_CONTROLLER_TRIALS (default 1) repeats the real-time tests (b, d) for longer trials.
// The fault drills (c) are in doc_controller_drills_test.cpp, the shared harness in
// doc_controller_harness.h; the ports above are the two files' together.
#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <numbers>
#include <thread>

#include "../runtime/test_support.h"
#include "doc_controller_harness.h"
#include "tests/support/dds_scope.h"
#include "tests/support/platform_gate.h"
#include "tests/support/real_time_run.h"
#include "tests/support/run_command_line.h"

namespace rths {
namespace {

using namespace doc_test;

// ------------------------------------------------------------------------------------------------
// a. Lockstep: the run through F32 frames equals the in-process run within the frames' resolution.
//
// The tolerance, from f32 at these scales: each value crossing an F32 field is rounded to 24 bits
// of mantissa, a relative error <= 2^-24 (6e-8); per step the target goes out rounded once and the
// displacement and force come back rounded once each, so the specimen force carries <= 3 x 2^-24
// of its value. The error enters the integrator as a force on a damped (zeta 0.05) oscillator,
// amplified at most 1 / (2 zeta) = 10 times, and a third of the stiffness is the specimen:
// |error| <= 3 x 2^-24 x 10 x peak|u| ~ 2e-6 peak|u|. Allowed: 1e-5 x peak |u| (5 x margin), on
// every DOF, command and realised drift, and 1e-5 x peak |force| on the force.
void lockstep_equals_in_process(const std::string& name, const std::string& case_name,
                                double pure_lag, int node_port, int peer_port) {
  const std::string text = study_text(2.0, 0.001, node_port, peer_port, "", "");
  const core::SimulationResult reference = test::reference_result(text, case_name);
  DocControllerOptions options = controller_options(peer_port, node_port, 0.001);
  options.pure_lag = pure_lag;
  DocController controller(options);
  const auto run = test::launch(name, text, case_name, test::scope_dds_to_this_test());
  controller.stop();
  ASSERT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  ASSERT_NE(run.record.footer(), nullptr);
  EXPECT_TRUE(run.record.footer()->ok()) << run.record.footer()->status();

  const auto steps = run.record.steps();
  ASSERT_EQ(steps.size(), reference.steps());
  const double peak_u = reference.displacement.cwiseAbs().maxCoeff();
  const double peak_f = reference.measured_force.cwiseAbs().maxCoeff();
  ASSERT_GT(peak_u, 1e-4) << "the motion must move the frame for the comparison to mean anything";
  const double tol_u = 1e-5 * peak_u, tol_f = 1e-5 * peak_f;
  double worst_u = 0, worst_f = 0;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    for (int i = 0; i < reference.displacement.cols(); ++i)
      worst_u =
          std::max(worst_u, std::abs(steps[k]->displacement(i) - reference.displacement(row, i)));
    for (int a = 0; a < reference.command.cols(); ++a) {
      worst_u = std::max(worst_u, std::abs(steps[k]->command(a) - reference.command(row, a)));
      worst_u = std::max(worst_u, std::abs(steps[k]->realised(a) - reference.realised(row, a)));
      worst_f = std::max(worst_f,
                         std::abs(steps[k]->measured_force(a) - reference.measured_force(row, a)));
    }
  }
  EXPECT_LE(worst_u, tol_u) << "peak |u| " << peak_u;
  EXPECT_LE(worst_f, tol_f) << "peak |f| " << peak_f;
  // It does differ: the frames are f32 (a run equal bit for bit would mean they were not used).
  EXPECT_GT(worst_u, 0.0);

  // What the rig saw: every step one run frame, counters 1, 2, 3..., the target the record's
  // command rounded to f32 mm; then HOLD before the STOP at the end of the completed run.
  const auto frames = controller.received();
  expect_counters_and_padding(frames);
  const auto run_only = run_frames(frames);
  ASSERT_EQ(run_only.size(), steps.size() - 1);
  for (const auto& f : run_only)
    ASSERT_EQ(f.target, test::through_f32(steps[f.counter]->command(0), test::kMm))
        << "frame " << f.counter;
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(frames.back().status, 2) << "the last frame is the STOP";
  bool hold_before_stop = false;
  for (const auto& f : frames) hold_before_stop = hold_before_stop || f.status == 1;
  EXPECT_TRUE(hold_before_stop) << "docs: HOLD comes before every STOP, also at the end";

  // The link report: nothing rejected, every step's answer accepted.
  const runtime::NodeRejects* rejects = node2(run.record);
  ASSERT_NE(rejects, nullptr);
  const runtime::ControllerReport& link = rejects->controller();
  EXPECT_EQ(link.frames_accepted(), steps.size() - 1);
  EXPECT_EQ(link.lost() + link.late() + link.wrong_source() + link.wrong_size() +
                link.repeated_counter() + link.unexpected_counter() + link.non_finite() +
                link.out_of_range() + link.bad_status() + link.implausible(),
            0u)
      << link.DebugString();
  EXPECT_GE(link.held_after(), 0.0) << "the controller answered held before the STOP";
}

TEST_F(DocControllerTest, LockstepThroughF32FramesEqualsInProcessWithinTheirResolution) {
  lockstep_equals_in_process("doc_lockstep_reference", "reference", 0.0, 47300, 47301);
}

// The plant's pure lag of 14 frames is the case's 14 ms shift at dt = 1 ms: the rig's lag stands
// in for the case's delay stage (a CONTROLLER node carries no delay stages of its own: the lab's
// rig is the delay).
TEST_F(DocControllerTest, LockstepWithTheRigsPureLagEqualsTheShiftCase) {
  lockstep_equals_in_process("doc_lockstep_shift", "lag_shift_14ms", 0.014, 47302, 47303);
}

// FrameField PADDING is "written 0, ignored when read" and controller.md's table says "a float
// field NaN or infinite (padding is never read)": a NaN in the feedback's F32 padding must not
// stop the run.
TEST_F(DocControllerTest, FeedbackPaddingIsNeverRead) {
  const std::string text = study_text(0.3, 0.001, 47330, 47331, "", "");
  DocControllerOptions options = controller_options(47331, 47330, 0.001);
  options.f32_padding = std::numeric_limits<float>::quiet_NaN();
  DocController controller(options);
  const auto run = test::launch("doc_padding", text, "reference", test::scope_dds_to_this_test());
  controller.stop();
  EXPECT_EQ(run.launch.coordinator_exit, 0) << test::read_file(run.launch.coordinator_log);
  const runtime::NodeRejects* rejects = node2(run.record);
  ASSERT_NE(rejects, nullptr);
  EXPECT_EQ(rejects->controller().non_finite(), 0u) << rejects->controller().DebugString();
}

// `rths launch` checks each lockstep run against the in-process run (commands.md, faults.md): a run
// through F32 frames cannot equal it bit for bit, and should be judged within the frames'
// resolution rather than fail as DIFFERS.
TEST_F(DocControllerTest, RthsLaunchAcceptsALockstepRunThroughF32Frames) {
  const auto dir = test::scratch_dir("doc_cli");
  const std::string text = study_text(
      1.0, 0.001, 47304, 47305, "", "domain_id: " + std::to_string(test::scope_dds_to_this_test()));
  const auto config = test::write_config(dir, text);
  const DocControllerOptions options = controller_options(47305, 47304, 0.001);
  DocController controller(options);
  const auto outcome = test::run_command_line(std::string(RTHS_BINARY_DIR) + "/cli/rths launch " +
                                              config.string() + " --case reference --no-plots " +
                                              "--timeout 60 --out " + (dir / "out").string());
  controller.stop();
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_EQ(outcome.output.find("DIFFERS"), std::string::npos) << outcome.output;
}

// ------------------------------------------------------------------------------------------------
// b. Real time, dt = 1/1024 s, a controller answering 2 ms after each frame: the node keeps
// several frames in flight, so the run does not hold, frames leave every dt and the answers the
// coordinator applies are about 2 ms + the loop's own round trip old.

// A real-time run that kept going to its end: completed, or (on a shared machine, not under
// timing targets) failed only by the one real-time verdict for this machine's own stalls. Never
// a HOLD, a node's fault or anything the link did, unless the machine itself stopped the loop
// (tests/support/real_time_run.h): the test is then skipped, naming both. Whatever the machine,
// the loop's CPU time per step stays under the suite's bound (never skipped).
void expect_ran_to_the_end(const test::LaunchedRun& run, const test::MeasuredPlatform& machine) {
  ASSERT_NE(run.record.footer(), nullptr) << test::read_file(run.launch.coordinator_log);
  const std::string& status = run.record.footer()->status();
  if (const auto why = test::loop_cpu_over_bound(test::read_file(run.launch.coordinator_log)))
    FAIL() << *why;
  if (run.launch.coordinator_exit == 0 && run.record.footer()->ok()) return;
  ASSERT_FALSE(timing_targets()) << status;
  if (status.rfind("completed with deadline misses", 0) == 0) return;
  if (const auto why = test::machine_stalled(status, *run.record.header(), machine))
    GTEST_SKIP() << *why;
  FAIL() << status << "\nthe machine meanwhile: " << machine.text;
}

void expect_real_time_run_healthy(const test::LaunchedRun& run, const DocController& controller,
                                  double answer_lag, const test::MeasuredPlatform& machine) {
  expect_ran_to_the_end(run, machine);
  if (testing::Test::IsSkipped() || testing::Test::HasFatalFailure()) return;
  const runtime::RunFooter* footer = run.record.footer();
  ASSERT_NE(footer, nullptr);
  const auto steps = run.record.steps();

  // No HOLD during the run: every step's frame went out as a run frame, and HOLD frames come
  // only after the last of them (the end of a completed run).
  const auto frames = controller.received();
  expect_counters_and_padding(frames);
  const auto run_only = run_frames(frames);
  EXPECT_EQ(run_only.size(), steps.size() - 1);
  bool seen_hold = false;
  for (const auto& f : frames) {
    if (f.status == 1) seen_hold = true;
    EXPECT_FALSE(seen_hold && f.status == 0) << "a run frame after a HOLD frame: the run held";
  }
  // Quiet, no frame is lost; on a shared machine a few may be, said in an event, within the
  // answer tolerance (counted below).
  for (const auto& e : run.record.entries)
    if (e.has_event() && timing_targets())
      EXPECT_EQ(e.event().what().find("lost"), std::string::npos) << e.event().what();

  // Frames every dt at the controller: the median interval of arrivals within 5 % of dt (25 %
  // on a shared machine: a backlog would read 2 ms, twice dt).
  std::vector<double> intervals;
  for (std::size_t i = 1; i < run_only.size(); ++i)
    intervals.push_back(static_cast<double>(run_only[i].receive_ns - run_only[i - 1].receive_ns) *
                        1e-9);
  const double interval = median(intervals);
  EXPECT_NEAR(interval, kRealTimeDt, (timing_targets() ? 0.05 : 0.25) * kRealTimeDt)
      << "median frame interval";

  // Pipelined: the answers left answer_lag after their frames (the controller's own clock).
  std::map<std::uint32_t, std::int64_t> arrived;
  for (const auto& f : run_only) arrived[f.counter] = f.receive_ns;
  std::vector<double> lag;
  for (const auto& a : controller.sent())
    if (arrived.count(a.counter))
      lag.push_back(static_cast<double>(a.send_ns - arrived[a.counter]) * 1e-9);
  EXPECT_NEAR(median(lag), answer_lag, 0.5e-3) << "the controller's own answer lag";

  // The answer age the coordinator applied: p99 x dt <= answer_lag + 1 ms + the loop's round trip
  // (3 ms for the 2 ms controller). The loop's round trip is the record's coordinator-side round
  // trip minus the node's frame round trip (what DDS and the two processes add), its p99.
  const runtime::NodeRejects* rejects = node2(run.record);
  ASSERT_NE(rejects, nullptr);
  const runtime::AnswerAge& age = rejects->answer_age();
  ASSERT_GT(age.steps_judged(), 0u);
  std::vector<double> loop, controller_round_trip;
  for (const runtime::StepRecord* s : steps)
    for (const runtime::LinkSample& link : s->links())
      if (link.node_id() == 2 && link.answered_step() > 0 && link.controller_round_trip() > 0) {
        loop.push_back(link.round_trip() - link.controller_round_trip());
        controller_round_trip.push_back(link.controller_round_trip());
      }
  const double loop_p99 = quantile(loop, 0.99);
  // The applied age is counted in whole steps (an answer is applied at the first step that
  // begins after it arrived), so the bound is rounded up to whole steps.
  const double age_p99 = age.p99_steps() * age.dt();
  const double bound = std::ceil((answer_lag + 1e-3 + loop_p99) / age.dt()) * age.dt();
  // On a shared machine (timing_targets() false) its stalls reach the p99: the bound is then
  // the answer window, which no applied answer may pass.
  EXPECT_LE(age_p99, timing_targets() ? bound : age.window_steps() * age.dt())
      << "answer age p99 " << age.p99_steps() << " steps x " << age.dt() << " s; loop p99 "
      << loop_p99 << " s; median " << age.median_steps() << ", max " << age.max_steps();
  // The node's frame round trip is the controller's lag plus loopback.
  EXPECT_NEAR(median(controller_round_trip), answer_lag, 0.5e-3);
  const runtime::ControllerReport& link = rejects->controller();
  EXPECT_EQ(link.wrong_size() + link.repeated_counter() + link.unexpected_counter() +
                link.non_finite() + link.out_of_range() + link.bad_status() + link.implausible(),
            0u)
      << link.DebugString();
  // Lost or late frames: none on a quiet machine; a shared one's stalls may lose a few (within
  // the answer tolerance, or the run would have failed above), 1 % of the frames; past that
  // beside a loaded machine (the witness's CPU share) the count is the machine's, named.
  const std::uint64_t lost_or_late = link.lost() + link.late();
  const std::uint64_t allowed = timing_targets() ? 0u : link.frames_sent() / 100;
  if (lost_or_late > allowed && !timing_targets() && machine.cpu_share < test::kLoadedCpuShare)
    GTEST_SKIP() << "this machine was loaded around the run (" << machine.text
                 << "): " << lost_or_late << " of " << link.frames_sent()
                 << " frames lost or late, over the 1 % a shared machine may lose";
  EXPECT_LE(lost_or_late, allowed) << link.DebugString();
  EXPECT_GE(link.in_flight(), 1u) << link.DebugString();
}

TEST_F(DocControllerTest, RealTimeAController2msBehindCostsAnswerAgeNotAHold) {
  for (int trial = 0; trial < trials(); ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const std::string text =
        study_text(2.0, kRealTimeDt, 47306, 47307,
                   "reply_timeout_ms: " + std::to_string(kReplyTimeoutMs), real_time_deployment());
    DocControllerOptions options = controller_options(47307, 47306, kRealTimeDt);
    options.answer_lag = 0.002;
    DocController controller(options);
    test::StallWitness witness;
    const auto run =
        test::launch("doc_real_time", text, "reference", test::scope_dds_to_this_test());
    const test::MeasuredPlatform machine = witness.finish();
    controller.stop();
    expect_real_time_run_healthy(run, controller, options.answer_lag, machine);
    if (IsSkipped()) return;
  }
}

// ------------------------------------------------------------------------------------------------
// d. A flood of 64 KiB datagrams (the largest UDP payload, 65507 bytes) and forged feedback-sized
// frames, sent to the node's port from another port all through a real-time run: the node's
// socket is connected to the controller, so the kernel drops them (controller.md) and the run
// completes with its link report clean.
TEST_F(DocControllerTest, AFloodFromAnotherPortDoesNotStopARealTimeRun) {
  for (int trial = 0; trial < trials(); ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const std::string text =
        study_text(2.0, kRealTimeDt, 47308, 47309,
                   "reply_timeout_ms: " + std::to_string(kReplyTimeoutMs), real_time_deployment());
    DocControllerOptions options = controller_options(47309, 47308, kRealTimeDt);
    options.answer_lag = 0.002;
    DocController controller(options);
    std::atomic<bool> done{false};
    std::atomic<long> flooded{0};
    std::thread rogue([&] {
      const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
      sockaddr_in from{}, to{};
      from.sin_family = to.sin_family = AF_INET;
      from.sin_addr.s_addr = to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      from.sin_port = htons(47399);
      to.sin_port = htons(47308);
      ::bind(s, reinterpret_cast<const sockaddr*>(&from), sizeof from);
      std::vector<std::uint8_t> big(65507, 0x5A), small(test::kDocFeedbackBytes, 0);
      std::uint32_t forged = 1;
      while (!done) {
        // Four 64 KiB datagrams and one forged answer (a plausible echo) per ms: 256 MB/s on
        // loopback, as much as this 2-core machine's other work leaves room for.
        for (int i = 0; i < 4; ++i)
          if (::sendto(s, big.data(), big.size(), 0, reinterpret_cast<const sockaddr*>(&to),
                       sizeof to) > 0)
            ++flooded;
        small[0] = static_cast<std::uint8_t>(forged >> 24);
        small[1] = static_cast<std::uint8_t>(forged >> 16);
        small[2] = static_cast<std::uint8_t>(forged >> 8);
        small[3] = static_cast<std::uint8_t>(forged);
        forged += 1;
        ::sendto(s, small.data(), small.size(), 0, reinterpret_cast<const sockaddr*>(&to),
                 sizeof to);
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      ::close(s);
    });
    test::StallWitness witness;
    const auto run = test::launch("doc_flood", text, "reference", test::scope_dds_to_this_test());
    const test::MeasuredPlatform machine = witness.finish();
    done = true;
    rogue.join();
    controller.stop();
    EXPECT_GT(flooded.load(), 1000) << "the flood must have been sent";
    expect_ran_to_the_end(run, machine);
    if (IsSkipped() || HasFatalFailure()) return;
    const runtime::NodeRejects* rejects = node2(run.record);
    ASSERT_NE(rejects, nullptr);
    // Every frame answered and accepted on a quiet machine; a shared one's stalls may lose a
    // few, never to the flood (the kernel drops it before the node's buffer).
    const std::uint64_t frames = run.record.steps().size() - 1;
    EXPECT_GE(rejects->controller().frames_accepted(),
              timing_targets() ? frames : frames - frames / 100)
        << rejects->controller().DebugString();
    EXPECT_EQ(rejects->controller().wrong_size(), 0u) << "the kernel drops them before the node";
  }
}

}  // namespace
}  // namespace rths
