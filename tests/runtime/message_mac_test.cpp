// MessageMac (transport/message_mac.h): every meaning field and the direction change the MAC;
// another key gives another; what the receiver stamps does not.
#include "transport/message_mac.h"

#include <gtest/gtest.h>

#include <functional>
#include <vector>

namespace rths::transport {
namespace {

const std::string kKey(64, 'a');

Message sample() {
  Message m;
  m.run_id = "run-1";
  m.node_id = 2;
  m.kind = 5;
  m.step = 17;
  m.sent_ns = 1'000'000;
  m.echo_ns = 999'000;
  m.payload = std::string("\x01\x00\x02", 3);
  return m;
}

TEST(MessageMac, VerifiesWhatItSignedUnderTheSameKey) {
  MessageMac signer(kKey), receiver(kKey);
  const Message m = sample();
  const Mac mac = signer.sign(m, m.sent_ns, Direction::kUp);
  EXPECT_TRUE(receiver.verify(m, Direction::kUp, mac));
  Message stamped = m;  // what the receiver stamps is not covered
  stamped.received_ns = 5;
  stamped.topic_node = 7;
  stamped.writer = 99;
  EXPECT_TRUE(receiver.verify(stamped, Direction::kUp, mac));
}

TEST(MessageMac, EveryMeaningFieldTheDirectionAndTheKeyChangeIt) {
  MessageMac mac(kKey);
  const Message m = sample();
  const Mac genuine = mac.sign(m, m.sent_ns, Direction::kUp);
  const std::vector<std::function<void(Message&)>> changes{
      [](Message& x) { x.run_id = "run-2"; },
      [](Message& x) { x.node_id = 1; },
      [](Message& x) { x.kind = 7; },
      [](Message& x) { x.step = 18; },
      [](Message& x) { x.sent_ns += 1; },
      [](Message& x) { x.echo_ns += 1; },
      [](Message& x) { x.payload.back() ^= 1; },
      [](Message& x) { x.payload += '\0'; },
      [](Message& x) {
        x.run_id = "run-";
        x.payload = "1" + x.payload;
      },
  };
  for (std::size_t i = 0; i < changes.size(); ++i) {
    Message changed = m;
    changes[i](changed);
    EXPECT_FALSE(mac.verify(changed, Direction::kUp, genuine)) << "change " << i;
  }
  EXPECT_FALSE(mac.verify(m, Direction::kDown, genuine)) << "a reflected message";
  MessageMac other(std::string(64, 'b'));
  EXPECT_FALSE(other.verify(m, Direction::kUp, genuine));
  EXPECT_FALSE(mac.verify(m, Direction::kUp, Mac{}));
}

TEST(MessageMac, TheSentStampGivenToSignIsTheOneCovered) {
  MessageMac mac(kKey);
  Message m = sample();
  m.sent_ns = 0;  // send() stamps it
  const Mac signed_at = mac.sign(m, 123, Direction::kDown);
  m.sent_ns = 123;
  EXPECT_TRUE(mac.verify(m, Direction::kDown, signed_at));
}

}  // namespace
}  // namespace rths::transport
