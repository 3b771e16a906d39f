#pragma once
// One UDP socket between this host and one peer (IPv4), bound to a configured local address and
// port only (never INADDR_ANY unless the config says 0.0.0.0). It is not connect()ed, so that a
// datagram from anyone else is seen, counted and named rather than dropped unseen by the kernel;
// receive() says whether each came from the configured peer.
//
//   UdpLink(local, local_port, peer, peer_port)  throws std::runtime_error naming the address
//                                                 when an address does not parse or bind fails.
//   send(bytes)            one datagram to the peer; false when the kernel refused it.
//   receive(deadline_ns)   the next datagram before the CLOCK_MONOTONIC deadline, or nullopt.
//                          Datagrams longer than kMaxDatagram are reported with their true size
//                          (truncated content).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rths::controller_node {

inline constexpr std::size_t kMaxDatagram = 2048;  // bytes read of one datagram

struct Datagram {
  std::vector<std::uint8_t> bytes;  // at most kMaxDatagram
  std::size_t size = 0;             // the datagram's true size
  bool from_peer = false;           // source address and port are the configured peer's
  std::string source;               // "a.b.c.d:port"
  std::int64_t received_ns = 0;     // CLOCK_MONOTONIC
};

class UdpLink {
 public:
  UdpLink(const std::string& local_address, int local_port, const std::string& peer_address,
          int peer_port);
  ~UdpLink();
  UdpLink(const UdpLink&) = delete;
  UdpLink& operator=(const UdpLink&) = delete;

  bool send(const std::vector<std::uint8_t>& bytes);
  std::optional<Datagram> receive(std::int64_t deadline_ns);
  std::string peer() const;   // "a.b.c.d:port"
  std::string local() const;  // "a.b.c.d:port"

 private:
  int fd_ = -1;
  std::uint32_t peer_address_ = 0;  // network order
  std::uint16_t peer_port_ = 0;     // network order
  std::string local_, peer_;
};

std::int64_t monotonic_ns();

}  // namespace rths::controller_node
