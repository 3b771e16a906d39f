// The DDS RAII layer and endpoint in one process (domain 30), the endpoint against a node
// process (the shared domain, scoped), and the in-process transport.
#include <gtest/gtest.h>

#include <thread>

#include "rths/proto/runtime.pb.h"
#include "runtime/launch/launch.h"
#include "tests/runtime/test_support.h"
#include "tests/support/dds_scope.h"
#include "transport/dds.h"
#include "transport/dds_endpoint.h"
#include "transport/in_process.h"

namespace rths::transport {
namespace {

using namespace std::chrono_literals;
constexpr std::uint32_t kDomain = 30;

class DdsTransport : public testing::Test {
 protected:
  static void SetUpTestSuite() { runtime::ensure_dds_config(); }
};

DdsEndpointOptions node_options(std::int32_t id, const std::string& prefix) {
  return {kDomain, false, id, prefix, 64};
}

TEST_F(DdsTransport, CoordinatorAndNodesExchangeMessagesAddressedByNodeId) {
  DdsEndpoint coordinator({kDomain, true, 0, "t_exchange", 64, {}, {}});
  DdsEndpoint node1(node_options(1, "t_exchange")), node2(node_options(2, "t_exchange"));
  coordinator.listen_to(1);
  coordinator.listen_to(2);
  coordinator.wait_for_match(0, 2, 5000ms);
  node1.wait_for_match(1, 0, 5000ms);
  node2.wait_for_match(1, 0, 5000ms);

  Message to2;
  to2.run_id = "r";
  to2.node_id = 2;
  to2.kind = 4;
  to2.step = 17;
  to2.payload = std::string("\x00\x01\x02", 3);
  coordinator.send(to2);
  const auto got = node2.receive(2s);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->step, 17);
  EXPECT_EQ(got->payload, to2.payload);  // embedded zero bytes survive
  EXPECT_GT(got->sent_ns, 0);
  EXPECT_GE(got->received_ns, got->sent_ns);
  EXPECT_FALSE(node1.receive(100ms).has_value()) << "node 1 must not see node 2's message";

  Message reply;
  reply.run_id = "r";
  reply.node_id = 2;
  reply.kind = 5;
  reply.step = 17;
  reply.echo_ns = got->sent_ns;
  node2.send(reply);
  const auto back = coordinator.receive(2s);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->echo_ns, got->sent_ns);
  EXPECT_EQ(back->node_id, 2);
  EXPECT_EQ(back->topic_node, 2);
  EXPECT_NE(back->writer, 0u);
  EXPECT_EQ(got->topic_node, 2) << "came on node 2's own command topic";
}

// The envelope's node id is a claim; the topic and the writer say who sent it. Node 1 claiming
// to be node 2 arrives stamped as node 1's topic, from another writer than node 2's.
TEST_F(DdsTransport, EachNodeSpeaksOnItsOwnTopicAndWriter) {
  DdsEndpoint coordinator({kDomain, true, 0, "t_own", 64, {}, {}});
  DdsEndpoint node1(node_options(1, "t_own")), node2(node_options(2, "t_own"));
  coordinator.listen_to(1);
  coordinator.listen_to(2);
  coordinator.listen_to(2);  // idempotent
  coordinator.wait_for_match(0, 2, 5000ms);
  node1.wait_for_match(1, 0, 5000ms);
  node2.wait_for_match(1, 0, 5000ms);
  Message m;
  m.run_id = "r";
  m.kind = 6;
  m.node_id = 2;
  node2.send(m);
  const auto genuine = coordinator.receive(2s);
  ASSERT_TRUE(genuine.has_value());
  node1.send(m);  // claims node 2
  const auto forged = coordinator.receive(2s);
  ASSERT_TRUE(forged.has_value());
  EXPECT_EQ(genuine->topic_node, 2);
  EXPECT_EQ(forged->node_id, 2);
  EXPECT_EQ(forged->topic_node, 1);
  EXPECT_NE(forged->writer, genuine->writer);
  // A broadcast travels on each addressed node's own topic: no topic is shared.
  Message to1 = m;
  to1.node_id = 1;
  coordinator.send(to1);
  ASSERT_TRUE(node1.receive(2s).has_value());
  Message broadcast;
  broadcast.node_id = kBroadcastId;
  broadcast.kind = 6;
  coordinator.send(broadcast);
  const auto heard = node1.receive(2s);
  ASSERT_TRUE(heard.has_value());
  EXPECT_EQ(heard->node_id, kBroadcastId);
  EXPECT_EQ(heard->topic_node, 1);
  EXPECT_FALSE(node2.receive(100ms).has_value()) << "node 2 was never addressed";
}

// One topic per addressee: a command for node 2 never reaches node 1's process at all (on a
// shared topic it woke node 1 to be thrown away), while a broadcast reaches both.
TEST_F(DdsTransport, AnAddressedMessageReachesOnlyItsNodesProcess) {
  DdsEndpoint coordinator({kDomain, true, 0, "t_addressed", 64, {}, {}});
  DdsEndpoint node1(node_options(1, "t_addressed")), node2(node_options(2, "t_addressed"));
  coordinator.listen_to(1);
  coordinator.listen_to(2);
  coordinator.wait_for_match(0, 2, 5000ms);
  Message to1;
  to1.run_id = "r";
  to1.node_id = 1;
  to1.kind = 6;
  coordinator.send(to1);  // node 1 addressed once, so a broadcast reaches it
  ASSERT_TRUE(node1.receive(2s).has_value());
  Message to2;
  to2.run_id = "r";
  to2.node_id = 2;
  to2.kind = 4;
  for (int step = 1; step <= 20; ++step) {
    to2.step = step;
    coordinator.send(to2);
  }
  for (int step = 1; step <= 20; ++step) {
    const auto got = node2.receive(2s);
    ASSERT_TRUE(got.has_value()) << "step " << step;
    EXPECT_EQ(got->step, step) << "addressed messages keep their order";
  }
  Message stop;
  stop.node_id = kBroadcastId;
  stop.kind = 8;
  coordinator.send(stop);
  ASSERT_TRUE(node1.receive(2s).has_value());
  ASSERT_TRUE(node2.receive(2s).has_value());
  EXPECT_EQ(node1.samples_taken(), 2u) << "node 1 took node 2's commands off the wire";
  EXPECT_EQ(node2.samples_taken(), 21u);
}

// With a run secret, what a participant without it (or with another) sends is dropped on the
// receive thread before the handler or receive() sees it, both ways, counted and named; what the
// run's own processes send arrives as before.
TEST_F(DdsTransport, WithARunSecretOnlyAuthenticatedMessagesArrive) {
  const std::string secret(64, 'c');
  DdsEndpoint coordinator({kDomain, true, 0, "t_mac", 64, {}, secret});
  DdsEndpointOptions own = node_options(1, "t_mac");
  own.run_secret = secret;
  DdsEndpointOptions stranger = node_options(1, "t_mac");
  stranger.run_secret = std::string(64, 'd');
  DdsEndpoint node1(own), plain(node_options(1, "t_mac")), other_key(stranger);
  coordinator.listen_to(1);
  coordinator.wait_for_match(0, 3, 5000ms);
  Message m;
  m.run_id = "r";
  m.node_id = 1;
  m.kind = 3;
  m.step = 4;
  m.payload = "ready";
  plain.send(m);
  other_key.send(m);
  node1.send(m);
  const auto got = coordinator.receive(2s);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->payload, "ready");
  EXPECT_FALSE(coordinator.receive(200ms).has_value()) << "a stranger's message arrived";
  const Unauthenticated dropped = coordinator.unauthenticated();
  EXPECT_EQ(dropped.count, 2u);
  EXPECT_NE(dropped.last.find("kind 3 as node 1 on node 1's topic, writer "), std::string::npos)
      << dropped.last;
  // Down: the coordinator's command reaches its node; a stranger coordinator's does not.
  DdsEndpoint plain_coordinator({kDomain, true, 0, "t_mac", 64, {}, {}});
  m.kind = 4;
  plain_coordinator.send(m);
  coordinator.send(m);
  const auto command = node1.receive(2s);
  ASSERT_TRUE(command.has_value());
  EXPECT_NE(command->writer, 0u);
  EXPECT_FALSE(node1.receive(200ms).has_value());
  EXPECT_EQ(node1.unauthenticated().count, 1u);
  // Up again: the stranger's writer is now known as a forger and its messages are dropped
  // unhashed, still counted; the run's own node (whose writer never failed) still arrives.
  m.kind = 3;
  for (int i = 0; i < 5; ++i) plain.send(m);
  node1.send(m);
  const auto again = coordinator.receive(2s);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->writer, got->writer);
  EXPECT_FALSE(coordinator.receive(200ms).has_value()) << "a known forger's message arrived";
  EXPECT_EQ(coordinator.unauthenticated().count, 2u + 5u);
}

TEST_F(DdsTransport, InterruptWakesABlockedReceive) {
  DdsEndpoint coordinator({kDomain, true, 0, "t_interrupt", 64, {}, {}});
  const auto start = std::chrono::steady_clock::now();
  std::thread waker([&] {
    std::this_thread::sleep_for(100ms);
    coordinator.interrupt();
  });
  EXPECT_FALSE(coordinator.receive(10s).has_value());
  waker.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, 5s);
}

TEST_F(DdsTransport, WaitForMatchTimesOutWithCounts) {
  DdsEndpoint lonely({kDomain, true, 0, "t_lonely", 64, {}, {}});
  try {
    lonely.wait_for_match(1, 1, 50ms);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("0/1 readers"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0/1 writers"), std::string::npos) << e.what();
  }
}

// The first message to a node leaves on a writer its reader has not discovered yet (we match
// their reader first). send() returns once the node has acknowledged it, so nothing written next
// reaches the node before its reader is in step with the writer: Cyclone dropped such a message
// and held every later one for its NackDelay (100 ms). A real node process: within one process
// Cyclone delivers locally, acknowledged at once.
TEST(DdsTransportToANodeProcess, TheFirstMessageToANodeIsAcknowledgedWhenSendReturns) {
  runtime::ensure_dds_config();
  const int domain = test::scope_dds_to_this_test();
  const auto dir = test::scratch_dir("first_message_acknowledged");
  util::ChildProcess node(
      test::program("rths-substructure-node", "substructure_nodes"),
      {"--node-id", "1", "--domain", std::to_string(domain), "--run-id", "first_ack", "--insecure"},
      dir / "node_1.log");
  DdsEndpointOptions options;
  options.domain_id = static_cast<std::uint32_t>(domain);
  DdsEndpoint coordinator(options);
  coordinator.listen_to(1);
  const auto announce = coordinator.receive(10s);
  ASSERT_TRUE(announce.has_value()) << node.log_tail();
  EXPECT_EQ(announce->kind, runtime::ANNOUNCE);
  EXPECT_FALSE(coordinator.acknowledged(1, 0ms)) << "nothing was addressed to node 1 yet";
  Message heartbeat;
  heartbeat.run_id = "first_ack";
  heartbeat.node_id = 1;
  heartbeat.kind = runtime::HEARTBEAT;
  coordinator.send(heartbeat);
  EXPECT_TRUE(coordinator.acknowledged(1, 0ms)) << node.log_tail();
  node.terminate();
}

TEST(DdsCheck, NamesTheCallAndTheReturnCode) {
  try {
    dds::check(-3, "dds_write");  // DDS_RETCODE_BAD_PARAMETER
    FAIL();
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("dds_write: ", 0), 0u) << what;
    EXPECT_GT(what.size(), std::string("dds_write: ").size());
  }
  EXPECT_EQ(dds::check(5, "ok"), 5);
}

TEST(DdsParticipant, BadDomainIsAnError) {
  EXPECT_THROW(dds::Participant(999999), std::runtime_error);
}

class Echo final : public NodeHandler {
 public:
  std::vector<Message> start() override { return {Message{"", 3, 1}}; }
  std::vector<Message> handle(const Message& m) override {
    Message r = m;
    r.echo_ns = m.sent_ns;
    return {r};
  }
};

TEST(InProcessTransport, DeliversToTheAddresseeAndQueuesReplies) {
  InProcessTransport transport;
  Echo echo;
  transport.attach(3, echo);
  const auto announce = transport.receive(0s);
  ASSERT_TRUE(announce.has_value());
  EXPECT_EQ(announce->node_id, 3);
  Message m;
  m.node_id = 3;
  m.step = 9;
  transport.send(m);
  const auto reply = transport.receive(0s);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->step, 9);
  EXPECT_GT(reply->echo_ns, 0);
  m.node_id = 4;  // nobody
  transport.send(m);
  EXPECT_FALSE(transport.receive(0s).has_value());
}

}  // namespace
}  // namespace rths::transport
