// MessageMac (transport/message_mac.h): every meaning field, the direction and the sending
// writer's GUID change the MAC; another key gives another; what the receiver stamps does not.
#include "transport/message_mac.h"

#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <atomic>
#include <functional>
#include <thread>
#include <vector>

namespace rths::transport {
namespace {

const std::string kKey(64, 'a');

// A writer's GUID (any 16 bytes: the MAC takes them as they are).
WriterGuid guid(std::uint8_t first) {
  WriterGuid g{};
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = static_cast<std::uint8_t>(first + i);
  return g;
}
const WriterGuid kWriter = guid(0x10);

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
  const Mac mac = signer.sign(m, m.sent_ns, Direction::kUp, kWriter);
  EXPECT_TRUE(receiver.verify(m, kWriter, Direction::kUp, mac));
  Message stamped = m;  // what the receiver stamps is not covered
  stamped.received_ns = 5;
  stamped.topic_node = 7;
  stamped.writer = 99;
  EXPECT_TRUE(receiver.verify(stamped, kWriter, Direction::kUp, mac));
}

TEST(MessageMac, EveryMeaningFieldTheDirectionAndTheKeyChangeIt) {
  MessageMac mac(kKey);
  const Message m = sample();
  const Mac genuine = mac.sign(m, m.sent_ns, Direction::kUp, kWriter);
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
    EXPECT_FALSE(mac.verify(changed, kWriter, Direction::kUp, genuine)) << "change " << i;
  }
  EXPECT_FALSE(mac.verify(m, kWriter, Direction::kDown, genuine)) << "a reflected message";
  MessageMac other(std::string(64, 'b'));
  EXPECT_FALSE(other.verify(m, kWriter, Direction::kUp, genuine));
  EXPECT_FALSE(mac.verify(m, kWriter, Direction::kUp, Mac{}));
}

// A genuine message re-published byte for byte by another writer is verified against that
// writer's GUID: it fails, whichever of the 16 bytes differs; the GUID it was signed for passes.
TEST(MessageMac, AnotherWritersGuidFailsAGenuineMessage) {
  MessageMac mac(kKey);
  const Message m = sample();
  const Mac genuine = mac.sign(m, m.sent_ns, Direction::kUp, kWriter);
  EXPECT_TRUE(mac.verify(m, kWriter, Direction::kUp, genuine));
  for (std::size_t byte = 0; byte < kWriter.size(); ++byte) {
    WriterGuid replayer = kWriter;
    replayer[byte] ^= 0x01;
    EXPECT_FALSE(mac.verify(m, replayer, Direction::kUp, genuine)) << "byte " << byte;
  }
  EXPECT_FALSE(mac.verify(m, guid(0x80), Direction::kUp, genuine));
  EXPECT_FALSE(mac.verify(m, WriterGuid{}, Direction::kUp, genuine));
  EXPECT_NE(mac.sign(m, m.sent_ns, Direction::kUp, guid(0x80)), genuine);
}

TEST(MessageMac, TheSentStampGivenToSignIsTheOneCovered) {
  MessageMac mac(kKey);
  Message m = sample();
  m.sent_ns = 0;  // send() stamps it
  const Mac signed_at = mac.sign(m, 123, Direction::kDown, kWriter);
  m.sent_ns = 123;
  EXPECT_TRUE(mac.verify(m, kWriter, Direction::kDown, signed_at));
}

// Little-endian, `bytes` wide.
std::string le(std::uint64_t value, int bytes) {
  std::string out;
  for (int i = 0; i < bytes; ++i) out += static_cast<char>((value >> (8 * i)) & 0xffu);
  return out;
}

TEST(MessageMac, IsStandardHmacSha256OverTheDocumentedEncoding) {
  const Message m = sample();
  const std::string key = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";
  // message_mac.h: tag (with its zero), direction, the writer's GUID (16 bytes as given), run id
  // and payload length-prefixed (4 bytes), node id and kind 4 bytes, step, sent_ns and echo_ns 8
  // bytes, little-endian.
  const std::string encoded = std::string("rths-mac-2", 11) + le(2, 1) +
                              std::string(kWriter.begin(), kWriter.end()) + le(m.run_id.size(), 4) +
                              m.run_id + le(2, 4) + le(5, 4) + le(17, 8) + le(1'000'000, 8) +
                              le(999'000, 8) + le(m.payload.size(), 4) + m.payload;
  for (const std::string& k : {key, std::string(100, 'k')}) {  // a key over one block is hashed
    Mac expected{};
    unsigned length = 0;
    HMAC(EVP_sha256(), k.data(), static_cast<int>(k.size()),
         reinterpret_cast<const unsigned char*>(encoded.data()), encoded.size(), expected.data(),
         &length);
    ASSERT_EQ(length, kMacBytes);
    EXPECT_EQ(MessageMac(k).sign(m, m.sent_ns, Direction::kUp, kWriter), expected) << k.size();
  }
}

TEST(MessageMac, SignsAndVerifiesFromManyThreadsAtOnce) {
  const MessageMac mac(kKey);
  const Message m = sample();
  const Mac genuine = mac.sign(m, m.sent_ns, Direction::kUp, kWriter);
  std::vector<std::thread> threads;
  std::atomic<int> wrong{0};
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      for (int i = 0; i < 20000; ++i) {
        if (mac.sign(m, m.sent_ns, Direction::kUp, kWriter) != genuine) ++wrong;
        if (!mac.verify(m, kWriter, Direction::kUp, genuine)) ++wrong;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(wrong, 0);
}

}  // namespace
}  // namespace rths::transport
