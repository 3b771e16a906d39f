#include "opensees_site/tcp_channel.h"

#include <gtest/gtest.h>

#include <vector>

#include "generic_client.h"

namespace rths::opensees {
namespace {

TEST(TcpChannel, LoopbackIsTellable) {
  EXPECT_TRUE(is_loopback("127.0.0.1"));
  EXPECT_TRUE(is_loopback("127.1.2.3"));
  EXPECT_FALSE(is_loopback("0.0.0.0"));
  EXPECT_FALSE(is_loopback("192.168.1.2"));
  EXPECT_FALSE(is_loopback("localhost"));
}

TEST(TcpChannel, BadAddressOrPortIsBadInput) {
  EXPECT_THROW(Listener("localhost", 0), std::invalid_argument);
  EXPECT_THROW(Listener("127.0.0.1", 70000), std::invalid_argument);
}

TEST(TcpChannel, ReadsExactlyAndTellsCloseTruncationAndTimeout) {
  Listener listener("127.0.0.1", 0);
  EXPECT_FALSE(listener.accept(std::chrono::milliseconds(10)).has_value());
  test::GenericClient client(listener.port(), 1, 8);
  auto server = listener.accept(std::chrono::seconds(2));
  ASSERT_TRUE(server.has_value());
  double sent[2] = {1.5, -2.5}, got[2] = {};
  client.send_bytes(sent, sizeof sent);
  auto r = server->read_exact(got, sizeof got, std::chrono::seconds(2));
  EXPECT_EQ(r.status, Connection::Read::kComplete);
  EXPECT_EQ(got[1], -2.5);
  r = server->read_exact(got, sizeof got, std::chrono::milliseconds(50));
  EXPECT_EQ(r.status, Connection::Read::kTimedOut);
  EXPECT_EQ(r.bytes, 0u);
  client.send_bytes(sent, 3);
  client.close();
  r = server->read_exact(got, sizeof got, std::chrono::seconds(2));
  EXPECT_EQ(r.status, Connection::Read::kTruncated);
  EXPECT_EQ(r.bytes, 3u);
  r = server->read_exact(got, sizeof got, std::chrono::seconds(2));
  EXPECT_EQ(r.status, Connection::Read::kClosed);
}

// A client that never reads its answers: once the socket's buffers are full, a write fails after
// the send timeout, naming the client, instead of blocking the site (65 s were measured).
TEST(TcpChannel, AClientThatStopsReadingFailsTheWriteAfterTheSendTimeout) {
  Listener listener("127.0.0.1", 0);
  test::GenericClient client(listener.port(), 1, 8);
  auto server = listener.accept(std::chrono::seconds(2));
  ASSERT_TRUE(server.has_value());
  server->set_send_timeout(std::chrono::milliseconds(100));
  const std::vector<char> chunk(1 << 20, 'x');
  const auto start = std::chrono::steady_clock::now();
  try {
    for (int i = 0; i < 1024; ++i) server->write_all(chunk.data(), chunk.size());
    FAIL() << "1 GiB written to a client that reads nothing";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("read nothing for the send timeout"), std::string::npos)
        << e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(30));
}

TEST(TcpChannel, FurtherClientsAreClosedWhileOneIsServed) {
  Listener listener("127.0.0.1", 0);
  test::GenericClient first(listener.port(), 1, 8);
  auto server = listener.accept(std::chrono::seconds(2));
  ASSERT_TRUE(server.has_value());
  test::GenericClient second(listener.port(), 1, 8);
  double x;
  server->read_exact(&x, sizeof x, std::chrono::milliseconds(100));  // polls the listener too
  EXPECT_TRUE(second.closed_by_server(2000));
  double one = 1.0;
  server->write_all(&one, sizeof one);
  double back = 0;
  EXPECT_TRUE(first.recv_bytes(&back, sizeof back));
  EXPECT_EQ(back, 1.0);
}

}  // namespace
}  // namespace rths::opensees
