#pragma once
// One UDP socket between this host and one peer (IPv4), bound to a configured local address and
// port only (never INADDR_ANY unless the config says 0.0.0.0) and connect()ed to the peer, so
// that the kernel drops every datagram from any other address or port before it takes room in
// the socket's receive buffer: a flood from another port can neither fill the buffer nor push
// the controller's answers out. (A sender that spoofs the peer's address and port still gets
// through: only a private link or VLAN closes that; docs/controller.md.)
//
//   UdpLink(local, local_port, peer, peer_port)  throws std::runtime_error naming the address
//                                                 when an address does not parse, or bind or
//                                                 connect fails.
//   send(bytes, size)      one datagram to the peer, never blocking: 0 when sent, else the
//                          errno. An ICMP error pending on the socket (ECONNREFUSED and kin,
//                          from the peer or forged by anyone) is counted and the datagram sent
//                          again once: such an error is no fault of this frame.
//   A socket filter (attached before bind) keeps only datagrams from the peer's address and
//   port, and datagrams that reached the socket before the connect are drained unread and
//   counted: a flood already running when the link opens never reaches try_receive().
//   icmp_errors(), last_icmp_errno(), drained_before_connect(): those counts.
//   wait(deadline_ns)      true when a datagram is ready before the CLOCK_MONOTONIC deadline.
//   try_receive(datagram)  the next queued datagram into a caller-owned Datagram, never
//                          blocking (false: none); no allocation. Datagrams longer than
//                          kMaxDatagram are reported with their true size (truncated content).
// Thread contract: send() and wait() may run on different threads at once (the socket calls are
// thread-safe); try_receive() on one thread at a time.
//
// DatagramLink is what the controller exchange needs of a link (the calls above, same
// contracts), so that its tests run on an in-process link with no ports
// (tests/controller_node/in_process_link.h); UdpLink is the real one.

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

#include "runtime/node/controller_link.h"
#include "runtime/rt/clock.h"

namespace rths::controller_node {

inline constexpr std::size_t kMaxDatagram =
    runtime::kMaxControllerFrameBytes;  // bytes read of one datagram

struct Datagram {
  std::array<std::uint8_t, kMaxDatagram> bytes{};  // the first min(size, kMaxDatagram) are valid
  std::size_t size = 0;                            // the datagram's true size
  bool from_peer = false;                          // source address and port are the peer's
  std::uint32_t source_address = 0;                // network order
  std::uint16_t source_port = 0;                   // network order
  std::int64_t received_ns = 0;                    // CLOCK_MONOTONIC
};

class DatagramLink {
 public:
  virtual ~DatagramLink() = default;
  // 0 when sent, else the errno; never blocks.
  virtual int send(const std::uint8_t* bytes, std::size_t size) = 0;
  // True when a datagram is ready before `deadline_ns` (CLOCK_MONOTONIC, or the link's clock).
  virtual bool wait(std::int64_t deadline_ns) const = 0;
  // The next queued datagram, never blocking; false: none.
  virtual bool try_receive(Datagram& datagram) = 0;
  virtual std::string peer() const = 0;  // "a.b.c.d:port"
  virtual std::uint64_t icmp_errors() const { return 0; }
  virtual int last_icmp_errno() const { return 0; }
  virtual std::uint64_t drained_before_connect() const { return 0; }
};

class UdpLink final : public DatagramLink {
 public:
  UdpLink(const std::string& local_address, int local_port, const std::string& peer_address,
          int peer_port);
  ~UdpLink() override;
  UdpLink(const UdpLink&) = delete;
  UdpLink& operator=(const UdpLink&) = delete;

  int send(const std::uint8_t* bytes, std::size_t size) override;
  bool wait(std::int64_t deadline_ns) const override;
  bool try_receive(Datagram& datagram) override;
  std::string peer() const override { return peer_; }  // "a.b.c.d:port"
  std::string local() const { return local_; }         // "a.b.c.d:port"
  std::uint64_t icmp_errors() const override {
    return icmp_errors_.load(std::memory_order_relaxed);
  }
  int last_icmp_errno() const override { return last_icmp_errno_.load(std::memory_order_relaxed); }
  std::uint64_t drained_before_connect() const override { return drained_; }

 private:
  int fd_ = -1;
  std::uint32_t peer_address_ = 0;  // network order
  std::uint16_t peer_port_ = 0;     // network order
  std::string local_, peer_;
  // send() and try_receive() may run on different threads: the counts are atomic.
  std::atomic<std::uint64_t> icmp_errors_{0};
  std::atomic<int> last_icmp_errno_{0};
  std::uint64_t drained_ = 0;
  void note_icmp(int error);
};

// An errno an ICMP error leaves on a connected UDP socket (port or host unreachable...).
bool icmp_errno(int error);

// The house's one monotonic clock (datagram stamps, deadlines), named here for the link's users.
using runtime::monotonic_ns;
// "a.b.c.d:port" of a datagram's source.
std::string source_text(const Datagram& datagram);

}  // namespace rths::controller_node
