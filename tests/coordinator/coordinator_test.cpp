// The coordinator's fail-safe and honest outcomes, on the in-process transport (the same
// coordinator and node services a DDS run uses, without threads): deadline misses fail a run,
// a node that stops answering stops it within max_missed_answers steps, a rate limit stops it
// before the offending command leaves, and an emulator that refuses a command stops it.
#include "coordinator/coordinator.h"
#include "coordinator/program.h"

#include <gtest/gtest.h>

#include <sched.h>
#include <functional>

#include <filesystem>
#include <limits>
#include <memory>
#include <thread>
#include <tuple>
#include <vector>

#include "actuator_emulator/actuator_service.h"
#include "runtime/node/schema.h"
#include "runtime/record/deadline_diagnosis.h"
#include "substructure_nodes/substructure_service.h"
#include "tests/runtime/test_support.h"
#include "tests/support/dds_scope.h"
#include "tests/support/real_time_run.h"
#include "transport/dds_endpoint.h"
#include "transport/in_process.h"
#include "util/process.h"
#include "view/feed.h"

namespace rths {
namespace {

using coordinator::RunOutcome;

// Forwards to a node service; drops the node's answers to steps after `mute_after` (a node that
// dies or stalls mid-run, seen from the coordinator).
class Muted final : public transport::NodeHandler {
 public:
  Muted(runtime::NodeService& service, std::int64_t mute_after)
      : service_(service), mute_after_(mute_after) {}
  std::vector<transport::Message> start() override { return service_.start(); }
  std::vector<transport::Message> handle(const transport::Message& m) override {
    auto replies = service_.handle(m);
    if (m.kind == runtime::COMMAND && m.step > mute_after_) replies.clear();
    return replies;
  }

 private:
  runtime::NodeService& service_;
  std::int64_t mute_after_;
};

// Forwards to a node service; at step `at` the node also sends a second, different answer to the
// same step (12345 N): a node that contradicts itself, or a forger in-process.
class Contradicting final : public transport::NodeHandler {
 public:
  Contradicting(runtime::NodeService& service, std::int64_t at) : service_(service), at_(at) {}
  std::vector<transport::Message> start() override { return service_.start(); }
  std::vector<transport::Message> handle(const transport::Message& m) override {
    auto replies = service_.handle(m);
    if (m.kind == runtime::COMMAND && m.step == at_ && !replies.empty()) {
      transport::Message forged = replies.front();
      runtime::Feedback f;
      runtime::unpack(forged, f);
      f.set_force(0, 12345.0);
      f.SerializeToString(&forged.payload);
      replies.push_back(forged);
    }
    return replies;
  }

 private:
  runtime::NodeService& service_;
  std::int64_t at_;
};

// Each clock read advances time by `step_ns`: 2 ms (more than a 1 ms period) makes every step
// find its deadline passed; 10 us makes a loop that keeps every deadline (sleeping jumps to it).
class FakeClock final : public runtime::PacingClock {
 public:
  explicit FakeClock(std::int64_t step_ns) : step_ns_(step_ns) {}
  std::int64_t now_ns() override { return now_ += step_ns_; }
  void sleep_until_ns(std::int64_t deadline) override { now_ = std::max(now_, deadline); }

 private:
  std::int64_t step_ns_;
  std::int64_t now_ = 1'000'000'000;
};

struct Cluster {
  transport::InProcessTransport transport;
  substructure_nodes::SubstructureService substructure{1, "run"};
  actuator_emulator::ActuatorService emulator{2, "run"};
  std::unique_ptr<Muted> muted;
};

RunOutcome run(const std::string& deployment, std::int64_t mute_node = 0,
               std::int64_t mute_after = 0, runtime::PacingClock* clock = nullptr,
               const std::string& case_name = "reference", double seconds = 0.5,
               std::function<transport::Unauthenticated()> unauthenticated = {}) {
  const study::PreparedStudy prepared = test::prepare(
      test::paper_frame_study(seconds,
                              "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: "
                              "ACTUATOR_EMULATOR } " +
                                  deployment + " }"));
  coordinator::CoordinatorOptions options;
  options.run_id = "run";
  options.case_name = case_name;
  options.clock = clock;
  options.unauthenticated = std::move(unauthenticated);
  Cluster c;
  coordinator::Coordinator coordinator(prepared, c.transport, options);
  runtime::NodeService& victim =
      mute_node == 1 ? static_cast<runtime::NodeService&>(c.substructure) : c.emulator;
  if (mute_node > 0) c.muted = std::make_unique<Muted>(victim, mute_after);
  c.transport.attach(
      1, mute_node == 1 ? static_cast<transport::NodeHandler&>(*c.muted) : c.substructure);
  c.transport.attach(2,
                     mute_node == 2 ? static_cast<transport::NodeHandler&>(*c.muted) : c.emulator);
  return coordinator.run();
}

// Each clock read advances time by 10 us, and the read that reaches `first_stall_ns` after its
// start (then every `every_ns` after that one, if > 0) jumps `stall_ns` more: the loop's thread
// stalled there (a stall longer than a period overruns that step and the ones after it until
// the loop catches up, about one step per period of stall).
class StallingClock final : public runtime::PacingClock {
 public:
  StallingClock(std::int64_t first_stall_ns, std::int64_t stall_ns, std::int64_t every_ns = 0)
      : next_stall_(now_ + first_stall_ns), stall_ns_(stall_ns), every_ns_(every_ns) {}
  std::int64_t now_ns() override {
    now_ += 10'000;
    if (now_ >= next_stall_) {
      now_ += stall_ns_;
      next_stall_ =
          every_ns_ > 0 ? next_stall_ + every_ns_ : std::numeric_limits<std::int64_t>::max();
    }
    return now_;
  }
  void sleep_until_ns(std::int64_t deadline) override { now_ = std::max(now_, deadline); }

 private:
  std::int64_t now_ = 1'000'000'000;
  std::int64_t next_stall_, stall_ns_, every_ns_;
};

// A real-time run (0.1 s, on time unless `clock` says otherwise) with a record; its outcome and
// the record's events.
struct RecordedRun {
  RunOutcome outcome;
  std::string events;  // one per line
};
RecordedRun run_recorded(const std::string& deployment, const std::string& record_name,
                         runtime::PacingClock* clock = nullptr, double seconds = 0.1) {
  const auto record = std::filesystem::temp_directory_path() / record_name;
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(
      seconds,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR " +
          deployment + " }"));
  coordinator::CoordinatorOptions options;
  options.run_id = "run";
  options.case_name = "reference";
  options.record = record;
  FakeClock on_time(10'000);
  options.clock = clock ? clock : &on_time;
  Cluster c;
  coordinator::Coordinator coordinator(prepared, c.transport, options);
  c.transport.attach(1, c.substructure);
  c.transport.attach(2, c.emulator);
  RecordedRun r;
  r.outcome = coordinator.run();
  for (const auto& entry : runtime::read_record(record).entries)
    if (entry.has_event()) r.events += entry.event().what() + "\n";
  return r;
}

// A case's link is the network in process: a distributed run of it is refused naming where its
// network is given, before any step, rather than run without the link the case names.
TEST(Coordinator, ACaseWithAnInProcessLinkIsRefusedNamingTheNodesLags) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(
      0.2,
      "cases { name: \"linked\" link { to_node { one_way_delay: 0.01 } } }\n"
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR } }"));
  coordinator::CoordinatorOptions options;
  options.run_id = "run";
  options.case_name = "linked";
  Cluster c;
  try {
    coordinator::Coordinator coordinator(prepared, c.transport, options);
    FAIL() << "a case with a link ran distributed";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("case 'linked' has a link"), std::string::npos) << what;
    EXPECT_NE(what.find("receive_lag and send_lag"), std::string::npos) << what;
  }
}

TEST(Coordinator, TwoDifferentAnswersToOneStepStopTheRunNamingTheNode) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(
      0.5,
      "deployment { nodes { id: 1 kind: SUBSTRUCTURE } nodes { id: 2 kind: ACTUATOR_EMULATOR } }"));
  coordinator::CoordinatorOptions options;
  options.run_id = "run";
  options.case_name = "reference";
  Cluster c;
  Contradicting node1(c.substructure, 100);
  coordinator::Coordinator coordinator(prepared, c.transport, options);
  c.transport.attach(1, node1);
  c.transport.attach(2, c.emulator);
  const RunOutcome o = coordinator.run();
  EXPECT_FALSE(o.ok);
  EXPECT_NE(o.status.find("integrity fault: two different answers to step 100 from node 1"),
            std::string::npos)
      << o.status;
  EXPECT_EQ(o.failed_node, "node 1 (substructure)");
  EXPECT_LE(o.result.steps(), 102u) << "stops within the step after the contradiction";
  EXPECT_EQ(c.emulator.held(), true) << "HOLD to the emulator";
  EXPECT_TRUE(c.substructure.stopped());
}

// After STOP, each node's last heartbeat reports what it rejected, and the outcome carries it.
TEST(Coordinator, TheOutcomeCarriesEveryNodesFinalRejectCounts) {
  const RunOutcome o = run("");
  ASSERT_TRUE(o.ok) << o.status;
  ASSERT_EQ(o.node_rejects.size(), 2u);
  EXPECT_EQ(o.node_rejects[0].label(), "node 1 (substructure)");
  EXPECT_EQ(o.node_rejects[1].node_id(), 2);
  for (const runtime::NodeRejects& n : o.node_rejects) {
    EXPECT_TRUE(n.final()) << n.label();
    EXPECT_EQ(runtime::RejectCounters::from(n.rejected()).total(), 0u) << n.label();
  }
}

TEST(Coordinator, RealTimeRunThatKeepsItsDeadlinesCompletes) {
  FakeClock on_time(10'000);
  const RunOutcome o = run("clock: REAL_TIME", 0, 0, &on_time);
  EXPECT_TRUE(o.ok) << o.status;
  EXPECT_EQ(o.status, "completed");
  EXPECT_EQ(o.counters.overruns(), 0u);
  // The loop thread's CPU time of each step after the first, bounded as the real-time tests
  // bound it (tests/support/real_time_run.h): a step that burns CPU fails whatever the load.
  EXPECT_EQ(o.step_cpu.count, o.result.steps() - 1);
  EXPECT_GT(o.step_cpu.median, 0.0);
  EXPECT_LE(o.step_cpu.median, test::kLoopCpuMedianBound);
}

// pin_loop gives the loop its CPU alone, and the record says so (a lab reading it later knows how
// the loop ran). The test thread is the loop thread here: its CPUs are given back afterwards.
TEST(Coordinator, PinLoopIsolatesTheLoopThreadAndTheRecordSaysSo) {
  cpu_set_t before;
  CPU_ZERO(&before);
  sched_getaffinity(0, sizeof before, &before);
  if (CPU_COUNT(&before) < 2) GTEST_SKIP() << "needs two CPUs";
  int highest = -1;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &before)) highest = c;
  const RecordedRun r =
      run_recorded("} clock: REAL_TIME max_overrun_fraction: -1 pin_loop: true loop_cpu: " +
                       std::to_string(highest),
                   "rths_coordinator_pin_loop.rthsrec");
  cpu_set_t during;
  CPU_ZERO(&during);
  sched_getaffinity(0, sizeof during, &during);
  sched_setaffinity(0, sizeof before, &before);
  EXPECT_TRUE(r.outcome.ok) << r.outcome.status;
  EXPECT_EQ(CPU_COUNT(&during), 1);
  EXPECT_TRUE(CPU_ISSET(highest, &during));
  EXPECT_NE(r.events.find("loop thread alone on CPU " + std::to_string(highest)), std::string::npos)
      << r.events;
}

// A real-time link whose injected round trip is longer than the loop's wait (half a step) cannot
// answer in time: the loop does not wait for it, says so, and still counts its answers as late.
TEST(Coordinator, RealTimeDoesNotWaitForALinkSlowerThanItsWait) {
  const RecordedRun r = run_recorded(
      "receive_lag { one_way_delay: 0.003 } send_lag { one_way_delay: 0.003 } } "
      "clock: REAL_TIME max_overrun_fraction: -1",
      "rths_coordinator_slow_link.rthsrec");
  EXPECT_TRUE(r.outcome.ok) << r.outcome.status;
  const std::string& events = r.events;
  EXPECT_NE(events.find("not waiting for the answers of node 2 (actuator emulator): its link "
                        "injects a 6.000000 ms round trip"),
            std::string::npos)
      << events;
  EXPECT_EQ(events.find("not waiting for the answers of node 1"), std::string::npos) << events;
}

TEST(Coordinator, DeadlineMissesBeyondTheToleranceFailTheRun) {
  FakeClock late(2'000'000);  // every step finds its deadline 2 ms gone
  const RunOutcome o = run("clock: REAL_TIME", 0, 0, &late);
  EXPECT_FALSE(o.ok);
  EXPECT_EQ(o.status.rfind("completed with deadline misses", 0), 0u) << o.status;
  EXPECT_EQ(o.counters.overruns(), o.counters.steps());
  EXPECT_EQ(o.counters.worst_overrun_streak(), o.counters.steps());
  EXPECT_EQ(o.result.steps(), 500u);  // it ran to the end: the outcome, not the run, is judged
}

// A real-time run that failed while its receivers dropped unauthenticated messages names the
// flood and its rate after its verdict; one that kept its deadlines under the same drops is not
// blamed on them, and lockstep never is.
TEST(Coordinator, AFailedRealTimeRunNamesTheUnauthenticatedFloodAndItsRate) {
  const auto flood = [] {
    return transport::Unauthenticated{5000, "kind 4 as node 1 on node 1's topic, writer 9"};
  };
  FakeClock late(2'000'000);
  const RunOutcome failed = run("clock: REAL_TIME", 0, 0, &late, "reference", 0.5, flood);
  EXPECT_FALSE(failed.ok);
  EXPECT_EQ(failed.status.rfind("completed with deadline misses", 0), 0u) << failed.status;
  EXPECT_NE(failed.status.find("; meanwhile 5000 unauthenticated messages ("), std::string::npos)
      << failed.status;
  EXPECT_NE(failed.status.find("a second) were dropped unread (coordinator 5000; newest: kind 4"),
            std::string::npos)
      << failed.status;
  FakeClock on_time(10'000);
  const RunOutcome kept = run("clock: REAL_TIME", 0, 0, &on_time, "reference", 0.5, flood);
  EXPECT_TRUE(kept.ok) << kept.status;
  EXPECT_EQ(kept.status, "completed");
}

// The fraction is the deployment's: 450 of 500 answers pass a stated 0.8, and fail a stated 0.95.
TEST(Coordinator, TheAnswerFractionIsTheDeployments) {
  const std::string base = "clock: REAL_TIME max_overrun_fraction: 1 max_missed_answers: 100000 ";
  FakeClock loose_clock(10'000), strict_clock(10'000);
  const RunOutcome loose = run(base + "min_answer_fraction: 0.8", 2, 450, &loose_clock);
  EXPECT_TRUE(loose.ok) << loose.status;
  const RunOutcome strict = run(base + "min_answer_fraction: 0.95", 2, 450, &strict_clock);
  EXPECT_FALSE(strict.ok);
  EXPECT_NE(strict.status.find("(at least 95 % needed)"), std::string::npos) << strict.status;
}

// -1 turns off the fraction only: isolated misses (a 1.5 ms stall every 100 ms, ~2 % of the
// steps) pass; one 50 ms stall, ~50 steps in a row past the fail-safe's 3-step window, does not.
TEST(Coordinator, AToleranceOfMinusOneAcceptsIsolatedDeadlineMissesButNoLongStreak) {
  StallingClock isolated(100'000'000, 1'500'000, 100'000'000);
  const RunOutcome o = run("clock: REAL_TIME max_overrun_fraction: -1", 0, 0, &isolated);
  EXPECT_TRUE(o.ok) << o.status;
  EXPECT_GT(o.counters.overruns(), 2u);
  EXPECT_LE(o.counters.worst_overrun_streak(), 3u);
  StallingClock stalled(200'000'000, 50'000'000);
  const RunOutcome streak = run("clock: REAL_TIME max_overrun_fraction: -1", 0, 0, &stalled);
  EXPECT_FALSE(streak.ok);
  EXPECT_GT(streak.counters.worst_overrun_streak(), 40u);
  EXPECT_EQ(streak.status.rfind("completed with deadline misses: " +
                                    std::to_string(streak.counters.worst_overrun_streak()) +
                                    " steps in a row overran, more than the fail-safe's window "
                                    "of 3",
                                0),
            0u)
      << streak.status;
  EXPECT_EQ(streak.result.steps(), 500u);  // it ran to the end: the outcome, not the run, is judged
}

// One record, one verdict: the coordinator's outcome (what `rths launch` exits on), what
// `rths identify` reads from the record's rows (diagnose_record_deadlines) and the view's badge
// agree, for a run on time, one with isolated misses within its 5 % tolerance, and the
// researcher's: a tolerance relaxed to 5 % and one long stall (~120 steps in a row, 12 %).
TEST(Coordinator, TheOutcomeIdentifyAndTheViewGiveOneVerdictOnOneRecord) {
  const auto record = std::filesystem::temp_directory_path() / "rths_coordinator_verdict.rthsrec";
  struct Trial {
    const char* name;
    std::unique_ptr<runtime::PacingClock> clock;
    bool ok;
  };
  std::vector<Trial> trials;
  trials.push_back({"on time", std::make_unique<FakeClock>(10'000), true});
  trials.push_back(
      {"isolated", std::make_unique<StallingClock>(100'000'000, 1'500'000, 100'000'000), true});
  trials.push_back(
      {"one long stall", std::make_unique<StallingClock>(300'000'000, 120'000'000), false});
  for (const Trial& t : trials) {
    SCOPED_TRACE(t.name);
    const RecordedRun r =
        run_recorded("} clock: REAL_TIME max_overrun_fraction: 0.05 max_missed_answers: 12",
                     record.filename().string(), t.clock.get(), 1.0);
    EXPECT_EQ(r.outcome.ok, t.ok) << r.outcome.status;
    const runtime::RecordContents contents = runtime::read_record(record);
    const auto identified = runtime::diagnose_record_deadlines(contents);
    ASSERT_TRUE(identified.has_value());
    EXPECT_EQ(identified->steps, r.outcome.counters.steps());
    EXPECT_EQ(identified->overruns, r.outcome.counters.overruns());
    EXPECT_EQ(identified->worst_streak, r.outcome.counters.worst_overrun_streak());
    EXPECT_EQ(identified->verdict.value_or("completed"), r.outcome.status);
    EXPECT_EQ(identified->usability.find("not a real-time test") != std::string::npos,
              !r.outcome.ok)
        << identified->usability;
    view::Feed feed;
    for (const runtime::RecordEntry& entry : contents.entries) feed.add(entry);
    view::FeedCursor cursor;
    const nlohmann::json status = feed.since(cursor)["status"];
    EXPECT_EQ(status["state"], r.outcome.ok ? "completed" : "failed");
    EXPECT_EQ(status["reason"], r.outcome.status);
  }
}

TEST(Coordinator, LockstepIsNeverJudgedOnDeadlines) {
  FakeClock late(2'000'000);
  EXPECT_TRUE(run("", 0, 0, &late).ok);
}

class SilentNode : public testing::TestWithParam<int> {};

TEST_P(SilentNode, StopsWithinMaxMissedAnswersAndNamesTheNode) {
  const int node = GetParam();
  FakeClock on_time(10'000);
  const std::int64_t last_answer = 200;
  const RunOutcome o = run("clock: REAL_TIME max_missed_answers: 3", node, last_answer, &on_time);
  EXPECT_FALSE(o.ok);
  EXPECT_EQ(o.failed_node, node == 1 ? "node 1 (substructure)" : "node 2 (actuator emulator)");
  EXPECT_NE(o.status.find("no answer for 3 consecutive steps"), std::string::npos) << o.status;
  // Steps 201, 202 and 203 went unanswered; 203 is not integrated, so 201 and 202 are the steps
  // integrated on an old force past the fault.
  EXPECT_EQ(o.result.steps(), static_cast<std::size_t>(last_answer + 3));
}

INSTANTIATE_TEST_SUITE_P(Nodes, SilentNode, testing::Values(1, 2),
                         [](const auto& info) { return "node_" + std::to_string(info.param); });

// A node whose answers stop arriving while max_missed_answers is too wide to fire (or, never
// having answered, never starts a streak) and liveliness has not run out: the run went to its
// end, but it is not ok, since the node answered fewer than the deployment's min_answer_fraction
// (0.99) of the steps.
TEST(Coordinator, ARunOnWhichANodeAnsweredTooFewStepsFails) {
  FakeClock on_time(10'000);
  const RunOutcome o =
      run("clock: REAL_TIME max_overrun_fraction: 1 max_missed_answers: 100000", 2, 450, &on_time);
  EXPECT_FALSE(o.ok) << o.status;
  EXPECT_EQ(o.status.rfind("failed: node 2 answered 450 of ", 0), 0u) << o.status;
  EXPECT_EQ(o.result.steps(), 500u);  // it ran to the end: the outcome, not the run, is judged
}

TEST(Coordinator, RateLimitStopsTheRunBeforeTheCommandLeaves) {
  // The frame moves by more than 10 nm per 1 ms step within its first 2 s.
  const RunOutcome o =
      run("limits { max_displacement_step: 1e-8 }", 0, 0, nullptr, "reference", 2.0);
  EXPECT_FALSE(o.ok);
  EXPECT_NE(o.status.find("per step); command not sent"), std::string::npos) << o.status;
  ASSERT_GT(o.result.steps(), 1u);
  const auto& u = o.result.displacement;
  for (Eigen::Index k = 1; k < u.rows(); ++k)
    EXPECT_LE(std::abs(u(k, 0) - u(k - 1, 0)), 1e-8) << "step " << k;
}

TEST(Coordinator, DivergedRunFailsAndKeepsTheStepsUpToIt) {
  const study::PreparedStudy prepared = test::prepare(test::paper_frame_study(2.0, ""));
  coordinator::CoordinatorOptions options;
  options.run_id = "run";
  options.divergence_bound = 5e-5;  // m: the frame passes 0.05 mm within its first 2 s
  Cluster c;
  coordinator::Coordinator coordinator(prepared, c.transport, options);
  c.transport.attach(1, c.substructure);
  c.transport.attach(2, c.emulator);
  const RunOutcome o = coordinator.run();
  EXPECT_FALSE(o.ok);
  EXPECT_EQ(o.status, "diverged");
  EXPECT_TRUE(o.result.diverged);
  ASSERT_GT(o.result.steps(), 2u);
  EXPECT_GT(o.result.displacement.bottomRows(1).cwiseAbs().maxCoeff(), 5e-5)
      << o.result.steps() << " steps, " << o.result.displacement.rows() << " rows; "
      << o.result.displacement.bottomRows(3);
  EXPECT_LE(o.result.displacement.topRows(o.result.steps() - 1).cwiseAbs().maxCoeff(), 5e-5);
}

// The summary counts steps as the record and `rths run` do: the initial state plus each
// commanded step (a coordinator that counted exchanges printed one fewer than `run`).
TEST(Coordinator, SummaryCountsStepsAsTheRecordDoes) {
  RunOutcome outcome;
  outcome.status = "completed";
  outcome.counters.set_steps(39069);
  const std::string text = coordinator::summary_text(outcome);
  EXPECT_NE(text.find("steps: 39070 recorded (39069 commanded)"), std::string::npos) << text;
}

// The summary prints the loop's CPU time per step as the real-time tests read it back.
TEST(Coordinator, SummaryNamesTheLoopsCpuTimePerStep) {
  RunOutcome outcome;
  outcome.status = "completed";
  const std::string without = coordinator::summary_text(outcome);
  EXPECT_EQ(without.find("loop CPU per step"), std::string::npos) << "no steps, no figure";
  outcome.step_cpu = runtime::summarize({0.1e-3, 0.25e-3, 0.3e-3});
  const std::string text = coordinator::summary_text(outcome);
  EXPECT_NE(text.find("loop CPU per step: median 0.25 ms, p99 0.3 ms, max 0.3 ms over 3 steps\n"),
            std::string::npos)
      << text;
  EXPECT_NEAR(test::loop_cpu_median(text).value_or(0.0), 0.25e-3, 1e-12);
  EXPECT_TRUE(test::loop_cpu_over_bound(text).has_value()) << "0.25 ms is over the bound";
}

// Each node's own unauthenticated drops (its heartbeat's count) are named on its line, apart
// from the coordinator's own on the summary's rejected line.
TEST(Coordinator, SummaryNamesEachSidesUnauthenticatedDrops) {
  RunOutcome outcome;
  outcome.status = "completed";
  outcome.unauthenticated.count = 3;
  outcome.unauthenticated.last = "kind 4 as node 1 on node 1's topic, writer 9";
  runtime::NodeRejects& node = outcome.node_rejects.emplace_back();
  node.set_node_id(1);
  node.set_label("node 1 (substructure)");
  node.mutable_rejected()->set_unauthenticated(11);
  node.set_final(true);
  const std::string text = coordinator::summary_text(outcome);
  EXPECT_NE(text.find(", unauthenticated 3 (dropped unread; newest: kind 4"), std::string::npos)
      << text;
  EXPECT_NE(text.find("node 1 (substructure) DDS messages rejected: foreign-run 0"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("out-of-range 0, unauthenticated 11\n"), std::string::npos) << text;
}

// The loop's set-up runs after every node is assigned, and a node whose coordinator is silent for
// its orphan timeout (2 s here) from its Assign holds and leaves. Here the set-up takes 3 s (an
// outside driver that waits before its step 0, as a large model's factorisation or an OpenSees
// model's start can), with real node processes over DDS: the set-up heartbeat keeps the nodes,
// and the real-time run completes, where before they left ("coordinator silent") before step 1.
TEST(Coordinator, NodesOverDdsWaitOutASetUpLongerThanTheirOrphanTimeout) {
  runtime::ensure_dds_config();
  const int domain = test::scope_dds_to_this_test();
  const std::string name = "long_set_up";
  const std::string text = test::paper_frame_study(
      0.3,
      "deployment { clock: REAL_TIME liveliness_timeout: 0.3 heartbeat_period: 0.02 "
      "max_missed_answers: 30 command_watchdog_periods: 30 max_overrun_fraction: -1 }");
  const auto dir = test::scratch_dir(name);
  std::vector<util::ChildProcess> nodes;
  for (const auto& [id, program, folder] :
       {std::tuple{"1", "rths-substructure-node", "substructure_nodes"},
        std::tuple{"2", "rths-actuator-emulator", "actuator_emulator"}})
    nodes.emplace_back(test::program(program, folder),
                       std::vector<std::string>{"--node-id", id, "--domain", std::to_string(domain),
                                                "--run-id", name, "--insecure"},
                       dir / (std::string("node_") + id + ".log"));
  study::PreparedStudy prepared = test::prepare(text);
  const core::HybridSetup setup =
      study::setup_for_case(prepared, study::find_case(prepared.config, "reference"));
  const core::GroundMotion motion = prepared.motion;
  transport::DdsEndpointOptions endpoint_options;
  endpoint_options.domain_id = static_cast<std::uint32_t>(domain);
  transport::DdsEndpoint endpoint(endpoint_options);
  coordinator::CoordinatorOptions options;
  options.run_id = name;
  options.case_name = "reference";
  options.record = dir / "run.rthsrec";
  options.driver = [&setup, &motion](core::HybridEvaluator& evaluator, core::StepHooks& hooks,
                                     core::SimulationResult& result) {
    std::this_thread::sleep_for(std::chrono::seconds(3));
    core::run_steps(setup, motion, evaluator, hooks, {}, result);
  };
  coordinator::Coordinator coordinator(std::move(prepared), endpoint, options);
  const RunOutcome outcome = coordinator.run();
  std::string logs;
  for (util::ChildProcess& node : nodes) {
    const int code = node.wait_for(std::chrono::seconds(10)).value_or(-1);
    logs += node.name() + " exit " + std::to_string(code) + ": " + node.log_tail() + "\n";
  }
  EXPECT_TRUE(outcome.ok) << outcome.status << "\n" << logs;
  EXPECT_EQ(outcome.result.steps(), motion.acceleration.size()) << logs;
  EXPECT_EQ(logs.find("coordinator silent"), std::string::npos) << logs;
}

// A model past kAllDofsLimit, launched over DDS in lockstep: the record keeps the DOFs the
// recorders' defaults keep (the header names them), each step holds those columns only, and they
// equal the in-process run's bit for bit.
TEST(Coordinator, ALargeModelsRecordOverDdsKeepsTheRecordedDofsOnly) {
  runtime::ensure_dds_config();
  const std::string text = test::uniform_storeys_study(250, 4e8, 0.1);
  const test::LaunchedRun run =
      test::launch("storeys250", text, "reference", test::scope_dds_to_this_test());
  ASSERT_EQ(run.launch.coordinator_exit, 0) << run.launch.coordinator_log_tail;
  const study::PreparedStudy prepared = test::prepare(text);
  const std::vector<int>& kept = prepared.recorders.kept_dofs;
  ASSERT_FALSE(kept.empty());
  const runtime::RunHeader* header = run.record.header();
  ASSERT_NE(header, nullptr);
  EXPECT_EQ(std::vector<int>(header->recorded_dofs().begin(), header->recorded_dofs().end()), kept);
  for (const runtime::StepRecord* step : run.record.steps())
    ASSERT_EQ(step->displacement_size(), static_cast<int>(kept.size()));
  test::expect_record_equals(
      run.record,
      core::simulate(
          study::setup_for_case(prepared, study::find_case(prepared.config, "reference")),
          prepared.motion,
          study::kept_by_recorders(prepared.recorders, prepared.config.deployment().limits())));
}
}  // namespace
}  // namespace rths
