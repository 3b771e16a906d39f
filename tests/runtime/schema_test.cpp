// Packing payloads into envelopes and back (runtime/node/schema.h).
#include "runtime/node/schema.h"

#include <gtest/gtest.h>

namespace rths::runtime {
namespace {

Command command_with(int drifts) {
  Command c;
  c.set_time(0.5);
  for (int i = 0; i < drifts; ++i) {
    c.add_drift(0.001 * (i + 1));
    c.add_drift_velocity(0.01 * (i + 1));
  }
  return c;
}

TEST(Schema, PackedPayloadUnpacksToTheSameMessage) {
  const Command sent = command_with(3);
  const transport::Message m = pack("run-7", 2, COMMAND, 41, sent);
  EXPECT_EQ(m.run_id, "run-7");
  EXPECT_EQ(m.node_id, 2);
  EXPECT_EQ(m.kind, COMMAND);
  EXPECT_EQ(m.step, 41);
  Command received;
  ASSERT_TRUE(unpack(m, received));
  EXPECT_EQ(received.SerializeAsString(), sent.SerializeAsString());
}

TEST(Schema, PackIntoReusesTheMessageBuffersAndResetsItsStamps) {
  transport::Message m;
  pack_into(m, "run-7", 2, COMMAND, 1, command_with(4));
  m.sent_ns = 5;
  m.echo_ns = 6;
  const char* payload_buffer = m.payload.data();
  const char* run_id_buffer = m.run_id.data();
  const std::size_t capacity = m.payload.capacity();
  // A payload no larger than before: same buffers, no allocation.
  pack_into(m, "run-7", 2, COMMAND, 2, command_with(3));
  EXPECT_EQ(m.payload.data(), payload_buffer);
  EXPECT_EQ(m.run_id.data(), run_id_buffer);
  EXPECT_EQ(m.payload.capacity(), capacity);
  EXPECT_EQ(m.step, 2);
  EXPECT_EQ(m.sent_ns, 0);  // send() stamps it afresh
  EXPECT_EQ(m.echo_ns, 0);
  Command received;
  ASSERT_TRUE(unpack(m, received));
  EXPECT_EQ(received.drift_size(), 3);
}

TEST(Schema, GarbageDoesNotUnpack) {
  transport::Message m;
  m.payload = "\xff\xff\xff";
  Feedback f;
  EXPECT_FALSE(unpack(m, f));
}

TEST(Schema, KindNamesAreReadableAndUnknownKindsSaySo) {
  EXPECT_EQ(kind_name(FEEDBACK), "FEEDBACK");
  EXPECT_EQ(kind_name(9999), "kind 9999");
  EXPECT_EQ(node_kind_name(config::NodeSpec::ACTUATOR_EMULATOR), "actuator emulator");
}

}  // namespace
}  // namespace rths::runtime
