// Node services driven message by message, without any transport.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>

#include "actuator_emulator/actuator_service.h"
#include "runtime/node/schema.h"
#include "substructure_nodes/substructure_service.h"
#include "test_support.h"

// Counts every allocation of this test program, so a command can be shown to allocate nothing.
namespace {
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace rths {
namespace {

constexpr char kRun[] = "run-1";

transport::Message assign_message(int node, config::NodeSpec::Kind kind, std::vector<int> storeys,
                                  std::vector<int> actuators, const std::string& extra = "") {
  runtime::Assign a;
  a.set_schema_version(runtime::kSchemaVersion);
  *a.mutable_study() = study::parse_study(test::paper_frame_study(1, extra), "t");
  a.set_case_name("lag_shift_14ms");
  a.mutable_node()->set_id(node);
  a.mutable_node()->set_kind(kind);
  a.set_dt(0.001);
  for (int s : storeys) a.add_storeys(s);
  for (int x : actuators) a.add_actuators(x);
  return runtime::pack(kRun, node, runtime::ASSIGN, 0, a);
}

transport::Message command(int node, std::int64_t step, double drift, double velocity) {
  runtime::Command c;
  c.set_time(0.001 * static_cast<double>(step));
  c.add_drift(drift);
  c.add_drift_velocity(velocity);
  auto m = runtime::pack(kRun, node, runtime::COMMAND, step, c);
  m.sent_ns = 1000 + step;
  return m;
}

// The synchronous path (node_service.h, "real time"): once warm, a command is checked, computed
// and answered into the service's own buffer without one allocation, for both kinds of node
// that answer with compute(). The messages are built before counting.
TEST(NodeService, ASynchronousCommandAllocatesNothingOnceWarm) {
  substructure_nodes::SubstructureService substructure(1, "");
  actuator_emulator::ActuatorService emulator(2, "");
  struct Case {
    runtime::NodeService& node;
    int id;
    config::NodeSpec::Kind kind;
  };
  for (const Case& c : {Case{substructure, 1, config::NodeSpec::SUBSTRUCTURE},
                        Case{emulator, 2, config::NodeSpec::ACTUATOR_EMULATOR}}) {
    const bool numerical = c.kind == config::NodeSpec::SUBSTRUCTURE;
    c.node.handle(assign_message(c.id, c.kind, numerical ? std::vector<int>{0} : std::vector<int>{},
                                 numerical ? std::vector<int>{} : std::vector<int>{0}));
    std::vector<transport::Message> commands;
    for (std::int64_t step = 1; step <= 200; ++step)
      commands.push_back(command(c.id, step, 1e-4 * static_cast<double>(step % 7), 0.0));
    long answers = 0;
    const runtime::NodeService::Send count_feedback = [&answers](const transport::Message& m) {
      answers += m.kind == runtime::FEEDBACK;
    };
    for (std::size_t k = 0; k < 10; ++k) c.node.handle(commands[k], count_feedback);
    const long before = allocations.load();
    for (std::size_t k = 10; k < commands.size(); ++k) c.node.handle(commands[k], count_feedback);
    EXPECT_EQ(allocations.load() - before, 0) << c.node.label();
    EXPECT_EQ(answers, 200) << c.node.label();
  }
}

TEST(SubstructureService, AnswersAssignThenCommandsWithStoreyShears) {
  substructure_nodes::SubstructureService node(1, "");
  ASSERT_EQ(node.start().size(), 1u);
  auto ready = node.handle(assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {}));
  ASSERT_EQ(ready.size(), 1u);
  runtime::Ready r;
  ASSERT_TRUE(runtime::unpack(ready[0], r));
  EXPECT_TRUE(r.error().empty()) << r.error();
  EXPECT_EQ(r.storeys(), 1);
  const auto reply = node.handle(command(1, 1, 0.01, 0.0));
  ASSERT_EQ(reply.size(), 1u);
  EXPECT_EQ(reply[0].kind, runtime::FEEDBACK);
  EXPECT_EQ(reply[0].echo_ns, 1001);
  runtime::Feedback f;
  ASSERT_TRUE(runtime::unpack(reply[0], f));
  // Numerical part: 2/3 of k = 1000 (4 pi)^2 N/m, linear.
  const double k = 1000.0 * std::pow(2 * M_PI / 0.5, 2) * (1 - 0.3333333333333333);
  EXPECT_NEAR(f.force(0), k * 0.01, 1e-6 * k * 0.01);
}

TEST(SubstructureService, RejectsDuplicatesForeignRunsAndGarbage) {
  substructure_nodes::SubstructureService node(1, "");
  node.handle(assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {}));
  EXPECT_EQ(node.handle(command(1, 1, 0.01, 0)).size(), 1u);
  EXPECT_TRUE(node.handle(command(1, 1, 0.01, 0)).empty());  // duplicate
  EXPECT_TRUE(node.handle(command(1, 3, 0.01, 0)).empty());  // lockstep: skips step 2
  auto foreign = command(1, 2, 0.01, 0);
  foreign.run_id = "other";
  EXPECT_TRUE(node.handle(foreign).empty());
  auto garbage = command(1, 2, 0.01, 0);
  garbage.payload = "\xff\xff";
  EXPECT_TRUE(node.handle(garbage).empty());
  auto wrong_size = command(1, 2, 0.01, 0);
  runtime::Command two;
  two.add_drift(1);
  two.add_drift(2);
  wrong_size.payload = two.SerializeAsString();
  EXPECT_TRUE(node.handle(wrong_size).empty());
  EXPECT_EQ(node.rejected().duplicate, 1u);
  EXPECT_EQ(node.rejected().out_of_order, 1u);
  EXPECT_EQ(node.rejected().foreign_run, 1u);
  EXPECT_EQ(node.rejected().garbage, 2u);
  EXPECT_EQ(node.handle(command(1, 2, 0.01, 0)).size(), 1u);  // the real step 2 still goes
}

// Control messages count only from the coordinator that assigned the node, on the node's own
// topic: never a broadcast, never another writer, never an empty run id.
TEST(SubstructureService, TakesControlOnlyFromItsCoordinatorOnItsOwnTopic) {
  substructure_nodes::SubstructureService node(1, "");
  auto broadcast_assign = assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {});
  broadcast_assign.node_id = broadcast_assign.topic_node = transport::kBroadcastId;
  EXPECT_TRUE(node.handle(broadcast_assign).empty());
  auto anonymous_assign = assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {});
  anonymous_assign.run_id.clear();
  EXPECT_TRUE(node.handle(anonymous_assign).empty());
  EXPECT_FALSE(node.assigned());
  auto assign = assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {});
  assign.writer = 5;
  ASSERT_EQ(node.handle(assign).size(), 1u);
  auto stranger = command(1, 1, 0.01, 0);
  stranger.writer = 6;
  EXPECT_TRUE(node.handle(stranger).empty());
  auto on_broadcast = command(1, 1, 0.01, 0);
  on_broadcast.writer = 5;
  on_broadcast.topic_node = on_broadcast.node_id = transport::kBroadcastId;
  EXPECT_TRUE(node.handle(on_broadcast).empty());
  auto stop = runtime::pack(kRun, 1, runtime::STOP, 1, runtime::Stop{});
  stop.writer = 6;
  EXPECT_TRUE(node.handle(stop).empty());
  EXPECT_FALSE(node.stopped());
  auto hold = runtime::pack(kRun, transport::kBroadcastId, runtime::HOLD, 1, runtime::Hold{});
  hold.writer = 5;
  EXPECT_TRUE(node.handle(hold).empty());
  EXPECT_FALSE(node.held());
  EXPECT_EQ(node.rejected().not_entitled, 5u);
  EXPECT_EQ(node.rejected().foreign_run, 1u);
  auto own = command(1, 1, 0.01, 0);
  own.writer = 5;
  EXPECT_EQ(node.handle(own).size(), 1u);
}

TEST(SubstructureService, RefusesACommandThatIsNotFiniteOrBeyondTheLimits) {
  substructure_nodes::SubstructureService node(1, "");
  node.handle(assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {},
                             "deployment { limits { max_displacement: 0.1 max_velocity: 1 } }"));
  EXPECT_TRUE(node.handle(command(1, 1, std::nan(""), 0)).empty());
  EXPECT_TRUE(node.handle(command(1, 1, 0.25, 0)).empty());  // beyond 2 x 0.1 m
  EXPECT_TRUE(node.handle(command(1, 1, 0.01, 1e300)).empty());
  auto bad_time = command(1, 1, 0.01, 0);
  runtime::Command c;
  ASSERT_TRUE(runtime::unpack(bad_time, c));
  c.set_time(std::numeric_limits<double>::infinity());
  bad_time.payload = c.SerializeAsString();
  EXPECT_TRUE(node.handle(bad_time).empty());
  EXPECT_EQ(node.rejected().out_of_range, 4u);
  EXPECT_EQ(node.handle(command(1, 1, 0.15, 0.5)).size(), 1u);
}

// STOP is answered by the node's last heartbeat: what it rejected, by cause, marked final.
TEST(SubstructureService, AnswersStopWithItsFinalRejectCounts) {
  substructure_nodes::SubstructureService node(1, "");
  node.handle(assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {}));
  auto foreign = command(1, 1, 0.01, 0);
  foreign.run_id = "other";
  node.handle(foreign);
  const auto replies = node.handle(runtime::pack(kRun, 1, runtime::STOP, 1, runtime::Stop{}));
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_TRUE(node.stopped());
  runtime::Heartbeat h;
  ASSERT_TRUE(runtime::unpack(replies[0], h));
  EXPECT_TRUE(h.final());
  EXPECT_EQ(h.rejected_by_cause().foreign_run(), 1u);
  EXPECT_EQ(h.rejected(), 1u);
}

// Each heartbeat carries, as rejected_by_cause's unauthenticated, what the node's transport
// counts at that moment (its source, asked anew each time), apart from its own rejects' total;
// without a source, 0.
TEST(SubstructureService, HeartbeatsCarryItsTransportsUnauthenticatedDrops) {
  substructure_nodes::SubstructureService node(1, "");
  node.handle(assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {}));
  runtime::Heartbeat h;
  ASSERT_TRUE(runtime::unpack(node.heartbeat(), h));
  EXPECT_EQ(h.rejected_by_cause().unauthenticated(), 0u);
  std::uint64_t dropped = 5;
  node.set_unauthenticated_source([&dropped] { return dropped; });
  ASSERT_TRUE(runtime::unpack(node.heartbeat(), h));
  EXPECT_EQ(h.rejected_by_cause().unauthenticated(), 5u);
  EXPECT_EQ(h.rejected(), 0u);
  dropped = 12;
  const auto replies = node.handle(runtime::pack(kRun, 1, runtime::STOP, 1, runtime::Stop{}));
  ASSERT_EQ(replies.size(), 1u);
  ASSERT_TRUE(runtime::unpack(replies[0], h));
  EXPECT_TRUE(h.final());
  EXPECT_EQ(h.rejected_by_cause().unauthenticated(), 12u);
}

TEST(SubstructureService, IgnoresAnAssignmentOfAnotherRunWhenTold) {
  substructure_nodes::SubstructureService node(1, "expected-run");
  EXPECT_TRUE(node.handle(assign_message(1, config::NodeSpec::SUBSTRUCTURE, {0}, {})).empty());
  EXPECT_FALSE(node.assigned());
}

TEST(SubstructureService, BadPartIsReportedInReady) {
  substructure_nodes::SubstructureService node(1, "");
  const auto ready = node.handle(assign_message(1, config::NodeSpec::SUBSTRUCTURE, {4}, {}));
  runtime::Ready r;
  ASSERT_TRUE(runtime::unpack(ready.at(0), r));
  EXPECT_NE(r.error().find("storey 5"), std::string::npos) << r.error();
}

TEST(ActuatorService, DelaysTheCommandInSimulatedTimeAndHolds) {
  actuator_emulator::ActuatorService node(2, "");
  node.handle(assign_message(2, config::NodeSpec::ACTUATOR_EMULATOR, {0}, {0}));
  runtime::Feedback f;
  // A 14 ms time shift: until t = 14 ms the specimen sees the first command.
  for (int k = 1; k <= 20; ++k) {
    const auto reply = node.handle(command(2, k, 0.001 * k, 1.0));
    ASSERT_EQ(reply.size(), 1u);
    ASSERT_TRUE(runtime::unpack(reply[0], f));
  }
  EXPECT_NEAR(f.realised(0), 0.001 * 6, 1e-12);  // u(t - 14 ms) at t = 20 ms
  node.handle(runtime::pack(kRun, 2, runtime::HOLD, 20, runtime::Hold{}));
  EXPECT_TRUE(node.held());
  EXPECT_TRUE(node.handle(command(2, 21, 1.0, 1.0)).empty());
  EXPECT_NEAR(node.held_position(0), 0.006, 1e-12);
}

// The interlock ramps the servo's target from where it was (20 mm, the newest command) back to
// where the specimen was when the hold began (6 mm, behind the 14 ms shift) at the rate limit, and
// the specimen comes to rest there: no change per period larger than the limit, target or realised.
TEST(ActuatorService, HoldRampsToRestAtTheRateLimitNeverInAJump) {
  actuator_emulator::ActuatorService node(2, "");
  node.handle(assign_message(2, config::NodeSpec::ACTUATOR_EMULATOR, {0}, {0},
                             "deployment { limits { max_displacement_step: 0.0015 } }"));
  for (int k = 1; k <= 20; ++k) ASSERT_EQ(node.handle(command(2, k, 0.001 * k, 1.0)).size(), 1u);
  node.handle(runtime::pack(kRun, 2, runtime::HOLD, 20, runtime::Hold{}));
  ASSERT_TRUE(node.held());
  ASSERT_EQ(node.hold_settles().size(), 1u);
  EXPECT_EQ(node.hold_settles()[0].ramp_ticks, 0);  // reported first, settled after
  node.settle_hold();
  const auto& h = node.hold_settles()[0];
  EXPECT_NEAR(h.from, 0.020, 1e-12);
  EXPECT_NEAR(h.position, 0.006, 1e-12);
  EXPECT_DOUBLE_EQ(h.max_change, 0.0015);
  EXPECT_EQ(h.ramp_ticks, 10);  // ceil(14 mm / 1.5 mm)
  EXPECT_LE(h.largest_target_change, 0.0015 + 1e-15);
  EXPECT_LE(h.largest_realised_change, 0.0015 + 1e-15);
  EXPECT_TRUE(h.settled);
  EXPECT_NEAR(h.realised, 0.006, 1e-6);
  EXPECT_NEAR(node.held_position(0), 0.006, 1e-12);
  node.settle_hold();  // once only
  EXPECT_EQ(node.hold_settles()[0].ramp_ticks, 10);
}

// Without a rate limit the ramp runs at the largest change between two commands of the run (1 mm
// here), never faster than the test itself moved.
TEST(ActuatorService, HoldWithoutARateLimitRampsAtTheRunsOwnLargestChange) {
  actuator_emulator::ActuatorService node(2, "");
  node.handle(assign_message(2, config::NodeSpec::ACTUATOR_EMULATOR, {0}, {0}));
  for (int k = 1; k <= 20; ++k) ASSERT_EQ(node.handle(command(2, k, 0.001 * k, 1.0)).size(), 1u);
  node.handle(runtime::pack(kRun, 2, runtime::HOLD, 20, runtime::Hold{}));
  node.settle_hold();
  const auto& h = node.hold_settles()[0];
  EXPECT_NEAR(h.max_change, 0.001, 1e-12);
  EXPECT_EQ(h.ramp_ticks, 14);
  EXPECT_LE(h.largest_target_change, 0.001 + 1e-12);
  EXPECT_TRUE(h.settled);
}

TEST(ActuatorService, LockstepServoRunsItsPeriodsPerCommandAndAnswersOnce) {
  actuator_emulator::ActuatorService node(2, "");
  node.handle(
      assign_message(2, config::NodeSpec::ACTUATOR_EMULATOR, {0}, {0}, "servo { rate: 4000 }"));
  EXPECT_FALSE(node.streaming());
  runtime::Feedback f;
  for (int k = 1; k <= 20; ++k) {
    const auto reply = node.handle(command(2, k, 0.001 * k, 1.0));
    ASSERT_EQ(reply.size(), 1u);
    ASSERT_TRUE(runtime::unpack(reply[0], f));
    EXPECT_EQ(f.servo_sample(), 0);
  }
  EXPECT_NEAR(f.realised(0), 0.006, 1e-12);  // the 14 ms shift, now over 56 servo periods
  EXPECT_FALSE(node.servo_tick(false).has_value());
}

TEST(ActuatorService, RealTimeServoStreamsOneFeedbackPerServoPeriodForTheNewestCommand) {
  actuator_emulator::ActuatorService node(2, "");
  node.handle(assign_message(2, config::NodeSpec::ACTUATOR_EMULATOR, {0}, {0},
                             "servo { rate: 4000 } deployment { clock: REAL_TIME }"));
  ASSERT_TRUE(node.streaming());
  EXPECT_DOUBLE_EQ(node.streaming_period(), 0.00025);
  EXPECT_FALSE(node.servo_tick(false).has_value());  // nothing commanded yet: nothing to say
  EXPECT_TRUE(node.handle(command(2, 1, 0.004, 1.0)).empty());  // loads the ramp only
  std::vector<std::int64_t> samples;
  for (int j = 0; j < 6; ++j) {
    const auto reply = node.servo_tick(j == 5);
    ASSERT_TRUE(reply.has_value());
    EXPECT_EQ(reply->kind, runtime::FEEDBACK);
    EXPECT_EQ(reply->step, 1);
    EXPECT_EQ(reply->echo_ns, 1001);
    runtime::Feedback f;
    ASSERT_TRUE(runtime::unpack(*reply, f));
    samples.push_back(f.servo_sample());
    EXPECT_GT(f.sampled_ns(), 0);
  }
  EXPECT_EQ(samples, (std::vector<std::int64_t>{1, 2, 3, 4, 5, 6}));
  const auto heartbeat = node.heartbeat();
  runtime::Heartbeat h;
  ASSERT_TRUE(runtime::unpack(heartbeat, h));
  EXPECT_EQ(h.servo_ticks(), 6u);
  EXPECT_EQ(h.servo_overruns(), 1u);
  node.handle(runtime::pack(kRun, 2, runtime::HOLD, 1, runtime::Hold{}));
  EXPECT_FALSE(node.servo_tick(false).has_value());  // held: the servo says and does nothing
}

TEST(ActuatorService, AStreamingServoRefusesAPerCommandSendStage) {
  actuator_emulator::ActuatorService node(2, "");
  runtime::Assign assign;
  ASSERT_TRUE(
      runtime::unpack(assign_message(2, config::NodeSpec::ACTUATOR_EMULATOR, {0}, {0},
                                     "servo { rate: 4000 } deployment { clock: REAL_TIME }"),
                      assign));
  assign.mutable_node()->add_send_delay()->mutable_shift()->set_delay(0.01);
  const auto ready = node.handle(runtime::pack(kRun, 2, runtime::ASSIGN, 0, assign));
  ASSERT_EQ(ready.size(), 1u);
  runtime::Ready r;
  ASSERT_TRUE(runtime::unpack(ready[0], r));
  EXPECT_NE(r.error().find("send_lag"), std::string::npos) << r.error();
}

}  // namespace
}  // namespace rths
