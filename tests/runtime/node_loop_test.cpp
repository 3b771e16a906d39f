// run_node against a scripted transport: announce until assigned, wait -> take -> answer, the
// final report on STOP, and the two ways a node leaves on its own (never assigned, orphaned).
#include "runtime/node/node_loop.h"

#include <gtest/gtest.h>

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "actuator_emulator/actuator_service.h"
#include "runtime/node/schema.h"
#include "substructure_nodes/substructure_service.h"
#include "test_support.h"

namespace rths::runtime {
namespace {

constexpr char kRun[] = "run-loop";

// Hands out the scripted messages (stamped on receipt unless the script stamped them) and keeps
// everything the node sends.
class ScriptedEndpoint final : public transport::Endpoint {
 public:
  void push(transport::Message m) {
    std::lock_guard lock(mutex_);
    script_.push_back(std::move(m));
    ready_.notify_one();
  }
  void send(const transport::Message& m) override {
    std::lock_guard lock(mutex_);
    sent_.push_back(m);
  }
  std::optional<transport::Message> receive(std::chrono::nanoseconds timeout) override {
    std::unique_lock lock(mutex_);
    if (!ready_.wait_for(lock, timeout, [&] { return !script_.empty(); })) return std::nullopt;
    transport::Message m = std::move(script_.front());
    script_.pop_front();
    m.sent_ns = m.sent_ns != 0 ? m.sent_ns : transport::realtime_ns();
    m.received_ns = m.received_ns != 0 ? m.received_ns : transport::realtime_ns();
    return m;
  }
  void interrupt() override {}
  int matched_peers() const override { return 1; }
  std::vector<transport::Message> sent() {
    std::lock_guard lock(mutex_);
    return sent_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<transport::Message> script_;
  std::vector<transport::Message> sent_;
};

transport::Message assign(int node, config::NodeSpec::Kind kind, double orphan_timeout = 5.0) {
  Assign a;
  a.set_schema_version(kSchemaVersion);
  *a.mutable_study() = study::parse_study(test::paper_frame_study(1, ""), "t");
  a.set_case_name("reference");
  a.mutable_node()->set_id(node);
  a.mutable_node()->set_kind(kind);
  a.set_dt(0.001);
  a.add_storeys(0);
  if (kind == config::NodeSpec::ACTUATOR_EMULATOR) a.add_actuators(0);
  a.set_heartbeat_period(0.05);
  a.set_orphan_timeout(orphan_timeout);
  return pack(kRun, node, ASSIGN, 0, a);
}

transport::Message command(int node, std::int64_t step) {
  Command c;
  c.set_time(0.001 * static_cast<double>(step));
  c.add_drift(0.001 * static_cast<double>(step));
  c.add_drift_velocity(0.0);
  transport::Message m = pack(kRun, node, COMMAND, step, c);
  m.sent_ns = 5000 + step;
  return m;
}

std::vector<transport::Message> of_kind(const std::vector<transport::Message>& sent,
                                        MessageKind kind) {
  std::vector<transport::Message> out;
  for (const auto& m : sent)
    if (m.kind == kind) out.push_back(m);
  return out;
}

TEST(NodeLoop, AnnouncesAnswersEachCommandAndReportsOnStop) {
  ScriptedEndpoint endpoint;
  substructure_nodes::SubstructureService service(1, kRun);
  endpoint.push(assign(1, config::NodeSpec::SUBSTRUCTURE));
  for (int step = 1; step <= 3; ++step) endpoint.push(command(1, step));
  endpoint.push(pack(kRun, 1, STOP, 3, Stop{}));
  EXPECT_EQ(run_node(endpoint, service, {}), 0);
  const auto sent = endpoint.sent();
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent.front().kind, ANNOUNCE);
  EXPECT_EQ(of_kind(sent, READY).size(), 1u);
  const auto answers = of_kind(sent, FEEDBACK);
  ASSERT_EQ(answers.size(), 3u);
  for (int step = 1; step <= 3; ++step) {
    EXPECT_EQ(answers[step - 1].step, step);
    EXPECT_EQ(answers[step - 1].echo_ns, 5000 + step) << "echoes its command's stamp";
  }
  Heartbeat last;
  ASSERT_TRUE(unpack(sent.back(), last));
  EXPECT_EQ(sent.back().kind, HEARTBEAT);
  EXPECT_TRUE(last.final());
}

TEST(NodeLoop, LeavesWhenNothingAssignsIt) {
  ScriptedEndpoint endpoint;
  substructure_nodes::SubstructureService service(1, kRun);
  NodeLoopOptions options;
  options.announce_period = 0.02;
  options.assign_timeout = 0.2;
  EXPECT_EQ(run_node(endpoint, service, options), 1);
  EXPECT_GE(of_kind(endpoint.sent(), ANNOUNCE).size(), 5u) << "announces until the timeout";
}

TEST(NodeLoop, AnOrphanedEmulatorHoldsAndLeaves) {
  ScriptedEndpoint endpoint;
  actuator_emulator::ActuatorService service(2, kRun);
  endpoint.push(assign(2, config::NodeSpec::ACTUATOR_EMULATOR, 0.3));
  endpoint.push(command(2, 1));
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(run_node(endpoint, service, {}), 1);
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(300));
  const auto holds = of_kind(endpoint.sent(), HOLD);
  ASSERT_EQ(holds.size(), 1u);
  Hold hold;
  ASSERT_TRUE(unpack(holds[0], hold));
  EXPECT_EQ(hold.reason(), "coordinator silent");
  EXPECT_GE(of_kind(endpoint.sent(), HEARTBEAT).size(), 2u) << "heartbeats while assigned";
}

// A node's own set-up (its part built on the Assign: a large model takes seconds) must not count
// as the coordinator's silence: the coordinator's heartbeats that queued meanwhile, stamped when
// they arrived, before the set-up ended, do not turn the orphan clock back. Here one arrived 3 s
// before it is taken, against a 2 s orphan timeout: the node stays and stops on STOP.
TEST(NodeLoop, MessagesThatQueuedDuringItsSetUpDoNotOrphanTheNode) {
  ScriptedEndpoint endpoint;
  actuator_emulator::ActuatorService service(2, kRun);
  endpoint.push(assign(2, config::NodeSpec::ACTUATOR_EMULATOR, 2.0));
  transport::Message queued = pack(kRun, transport::kBroadcastId, HEARTBEAT, 0, Heartbeat{});
  queued.received_ns = transport::realtime_ns() - 3'000'000'000;
  endpoint.push(queued);
  std::thread stop([&endpoint] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    endpoint.push(pack(kRun, 2, STOP, 0, Stop{}));
  });
  EXPECT_EQ(run_node(endpoint, service, {}), 0);
  stop.join();
  EXPECT_TRUE(of_kind(endpoint.sent(), HOLD).empty());
}

}  // namespace
}  // namespace rths::runtime
