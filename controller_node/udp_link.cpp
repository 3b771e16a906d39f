#include "controller_node/udp_link.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace rths::controller_node {
namespace {

sockaddr_in address_of(const std::string& address, int port, const std::string& what) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  if (port < 1 || port > 65535)
    throw std::runtime_error(what + " port " + std::to_string(port) + " is not in [1, 65535]");
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1)
    throw std::runtime_error(what + " address '" + address + "' is not an IPv4 address");
  return a;
}

std::string text_of(const sockaddr_in& a) {
  char host[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &a.sin_addr, host, sizeof host);
  return std::string(host) + ":" + std::to_string(ntohs(a.sin_port));
}

}  // namespace

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

UdpLink::UdpLink(const std::string& local_address, int local_port, const std::string& peer_address,
                 int peer_port) {
  const sockaddr_in local = address_of(local_address, local_port, "local");
  const sockaddr_in peer = address_of(peer_address, peer_port, "peer");
  peer_address_ = peer.sin_addr.s_addr;
  peer_port_ = peer.sin_port;
  local_ = text_of(local);
  peer_ = text_of(peer);
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    const std::string why = std::strerror(errno);
    close(fd_);
    throw std::runtime_error("cannot bind UDP " + local_ + ": " + why);
  }
}

UdpLink::~UdpLink() {
  if (fd_ >= 0) close(fd_);
}

std::string UdpLink::peer() const { return peer_; }
std::string UdpLink::local() const { return local_; }

bool UdpLink::send(const std::vector<std::uint8_t>& bytes) {
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = peer_address_;
  to.sin_port = peer_port_;
  const ssize_t n =
      sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  return n == static_cast<ssize_t>(bytes.size());
}

std::optional<Datagram> UdpLink::receive(std::int64_t deadline_ns) {
  for (;;) {
    const std::int64_t left = deadline_ns - monotonic_ns();
    if (left <= 0) return std::nullopt;
    pollfd p{fd_, POLLIN, 0};
    const int ms = static_cast<int>((left + 999999) / 1000000);
    const int ready = poll(&p, 1, ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // the deadline is checked again above
    Datagram d;
    d.bytes.resize(kMaxDatagram);
    sockaddr_in from{};
    socklen_t from_size = sizeof from;
    const ssize_t n = recvfrom(fd_, d.bytes.data(), d.bytes.size(), MSG_TRUNC,
                               reinterpret_cast<sockaddr*>(&from), &from_size);
    if (n < 0) continue;  // e.g. ICMP port unreachable reported on the socket
    d.received_ns = monotonic_ns();
    d.size = static_cast<std::size_t>(n);
    d.bytes.resize(std::min(d.size, kMaxDatagram));
    d.from_peer = from.sin_addr.s_addr == peer_address_ && from.sin_port == peer_port_;
    d.source = text_of(from);
    return d;
  }
}

}  // namespace rths::controller_node
