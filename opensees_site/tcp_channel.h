#pragma once
// The TCP side of an OpenSees site: one listening socket and one client at a time.
//
//   Listener     binds address:port (port 0 = a free one, then port() says which); TCP_NODELAY
//                on every accepted client, as genericClient's TCP_Socket sets on its side.
//   Connection   reads exactly N bytes within a deadline and writes whole buffers. While it
//                waits it also accepts and closes any further client on the listener, logging
//                the refusal, so a second OpenSees never shares the actuators.
// Quick ACKs after every read: genericClient leaves Nagle on, and a delayed ACK of a frame that
// gets no answer would hold its next frame back 40 ms.
// Bytes are the host's: genericClient sends native ints and doubles without an endianness check.

#include <chrono>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>

namespace rths::opensees {

class Listener;

class Connection {
 public:
  enum class Read { kComplete, kClosed, kTruncated, kTimedOut };
  struct ReadResult {
    Read status = Read::kComplete;
    std::size_t bytes = 0;  // read before the end, the close or the deadline
  };
  Connection(int fd, std::string peer, Listener* listener);
  Connection(Connection&& other) noexcept;
  Connection& operator=(Connection&&) = delete;
  Connection(const Connection&) = delete;
  ~Connection();

  // kClosed: the peer closed before the first byte; kTruncated: after some, before the last.
  // timeout < 0: no deadline. Allocates nothing.
  ReadResult read_exact(void* data, std::size_t size, std::chrono::nanoseconds timeout);
  // Throws std::runtime_error when the peer is gone, or when it has read nothing for the send
  // timeout (set_send_timeout) while the socket's buffers are full. Allocates nothing but the
  // message of what it throws.
  void write_all(const void* data, std::size_t size);
  // Bounds every write (SO_SNDTIMEO; 0: no bound, the default): a client that stops reading can
  // no longer block the site in send() for as long as its buffers stay full.
  void set_send_timeout(std::chrono::nanoseconds timeout);
  // Ends the exchange in both directions now (shutdown): a client blocked waiting for an answer
  // reads the close at once and fails its analysis, rather than wait for a force that will not
  // come. The descriptor is closed by the destructor. Allocates nothing.
  void end();
  const std::string& peer() const { return peer_; }

 private:
  int fd_ = -1;
  std::string peer_;
  Listener* listener_ = nullptr;
  double send_timeout_seconds_ = 0.0;  // for the message
};

class Listener {
 public:
  // Throws std::invalid_argument for an address that is not an IPv4 literal or a port outside
  // 0..65535, std::runtime_error naming address:port and the reason when it cannot bind.
  Listener(const std::string& address, int port);
  ~Listener();
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;

  int port() const { return port_; }
  const std::string& address() const { return address_; }
  int fd() const { return fd_; }
  // Waits up to `timeout` (< 0: forever) for a client; nullopt when none came.
  std::optional<Connection> accept(std::chrono::milliseconds timeout);
  // Accepts and closes every client waiting now; each refusal is logged with `why`.
  int refuse_waiting(const std::string& why);

 private:
  int fd_ = -1;
  int port_ = 0;
  std::string address_;
};

// Whether an IPv4 literal is a loopback address (127.0.0.0/8).
bool is_loopback(const std::string& address);

}  // namespace rths::opensees
