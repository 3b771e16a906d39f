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
//   send(bytes, size)      one datagram to the peer, never blocking; false when the kernel
//                          refused it (buffer full, ICMP error pending).
//   wait(deadline_ns)      true when a datagram is ready before the CLOCK_MONOTONIC deadline.
//   try_receive(datagram)  the next queued datagram into a caller-owned Datagram, never
//                          blocking (false: none); no allocation. Datagrams longer than
//                          kMaxDatagram are reported with their true size (truncated content).
// Thread contract: send() and wait() may run on different threads at once (the socket calls are
// thread-safe); try_receive() on one thread at a time.

#include <array>
#include <cstdint>
#include <string>

#include "runtime/node/controller_link.h"

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

class UdpLink {
 public:
  UdpLink(const std::string& local_address, int local_port, const std::string& peer_address,
          int peer_port);
  ~UdpLink();
  UdpLink(const UdpLink&) = delete;
  UdpLink& operator=(const UdpLink&) = delete;

  bool send(const std::uint8_t* bytes, std::size_t size);
  bool wait(std::int64_t deadline_ns) const;
  bool try_receive(Datagram& datagram);
  std::string peer() const { return peer_; }    // "a.b.c.d:port"
  std::string local() const { return local_; }  // "a.b.c.d:port"

 private:
  int fd_ = -1;
  std::uint32_t peer_address_ = 0;  // network order
  std::uint16_t peer_port_ = 0;     // network order
  std::string local_, peer_;
};

std::int64_t monotonic_ns();
// "a.b.c.d:port" of a datagram's source.
std::string source_text(const Datagram& datagram);

}  // namespace rths::controller_node
