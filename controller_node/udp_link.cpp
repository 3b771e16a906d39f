#include "controller_node/udp_link.h"

#include <arpa/inet.h>
#include <linux/filter.h>
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

std::string text_of(std::uint32_t address, std::uint16_t port) {
  in_addr a{};
  a.s_addr = address;
  char host[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &a, host, sizeof host);
  return std::string(host) + ":" + std::to_string(ntohs(port));
}

// A socket filter, attached before bind, that keeps only the peer's datagrams: connect() alone
// leaves a window in which a datagram the kernel matched to the socket before the connect is
// queued after it (a flood already running when the node starts).
void accept_only_the_peer(int fd, const sockaddr_in& peer) {
  // At the filter, the packet starts at the UDP header; the IPv4 header lies before it.
  sock_filter code[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, static_cast<__u32>(SKF_NET_OFF + 12)),  // IPv4 source
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, ntohl(peer.sin_addr.s_addr), 0, 3),
      BPF_STMT(BPF_LD | BPF_H | BPF_ABS, 0),  // UDP source port
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, ntohs(peer.sin_port), 0, 1),
      BPF_STMT(BPF_RET | BPF_K, 0xFFFFFFFFu),
      BPF_STMT(BPF_RET | BPF_K, 0),
  };
  const sock_fprog program{static_cast<unsigned short>(sizeof code / sizeof code[0]), code};
  if (setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &program, sizeof program) != 0) {
    const std::string why = std::strerror(errno);
    close(fd);
    throw std::runtime_error("cannot filter the UDP socket to its peer: " + why);
  }
}

}  // namespace

std::string source_text(const Datagram& datagram) {
  return text_of(datagram.source_address, datagram.source_port);
}

UdpLink::UdpLink(const std::string& local_address, int local_port, const std::string& peer_address,
                 int peer_port) {
  const sockaddr_in local = address_of(local_address, local_port, "local");
  const sockaddr_in peer = address_of(peer_address, peer_port, "peer");
  peer_address_ = peer.sin_addr.s_addr;
  peer_port_ = peer.sin_port;
  local_ = text_of(local.sin_addr.s_addr, local.sin_port);
  peer_ = text_of(peer_address_, peer_port_);
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  accept_only_the_peer(fd_, peer);
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    const std::string why = std::strerror(errno);
    close(fd_);
    throw std::runtime_error("cannot bind UDP " + local_ + ": " + why);
  }
  if (connect(fd_, reinterpret_cast<const sockaddr*>(&peer), sizeof peer) != 0) {
    const std::string why = std::strerror(errno);
    close(fd_);
    throw std::runtime_error("cannot connect UDP " + local_ + " to " + peer_ + ": " + why);
  }
  std::array<std::uint8_t, 1> scrap{};
  for (;;) {
    const ssize_t n = recv(fd_, scrap.data(), scrap.size(), MSG_TRUNC | MSG_DONTWAIT);
    if (n >= 0)
      ++drained_;
    else if (errno != EINTR && !icmp_errno(errno))
      break;
  }
}

bool icmp_errno(int error) {
  return error == ECONNREFUSED || error == EHOSTUNREACH || error == ENETUNREACH ||
         error == EHOSTDOWN || error == ENETDOWN || error == EPROTO || error == ENOPROTOOPT;
}

void UdpLink::note_icmp(int error) {
  icmp_errors_.fetch_add(1, std::memory_order_relaxed);
  last_icmp_errno_.store(error, std::memory_order_relaxed);
}

UdpLink::~UdpLink() {
  if (fd_ >= 0) close(fd_);
}

int UdpLink::send(const std::uint8_t* bytes, std::size_t size) {
  // A pending ICMP error fails one send and is cleared by it: the second try carries the frame.
  for (int attempt = 0;; ++attempt) {
    const ssize_t n = ::send(fd_, bytes, size, MSG_DONTWAIT);
    if (n == static_cast<ssize_t>(size)) return 0;
    const int error = n < 0 ? errno : EMSGSIZE;
    if (error == EINTR) continue;
    if (!icmp_errno(error)) return error;
    note_icmp(error);
    if (attempt == 1) return error;
  }
}

bool UdpLink::wait(std::int64_t deadline_ns) const {
  for (;;) {
    const std::int64_t left = deadline_ns - monotonic_ns();
    if (left <= 0) return false;
    pollfd p{fd_, POLLIN, 0};
    timespec timeout{static_cast<time_t>(left / 1000000000), static_cast<long>(left % 1000000000)};
    const int ready = ppoll(&p, 1, &timeout, nullptr);
    if (ready < 0 && errno == EINTR) continue;
    return ready > 0;
  }
}

bool UdpLink::try_receive(Datagram& d) {
  for (;;) {
    sockaddr_in from{};
    socklen_t from_size = sizeof from;
    const ssize_t n = recvfrom(fd_, d.bytes.data(), d.bytes.size(), MSG_TRUNC | MSG_DONTWAIT,
                               reinterpret_cast<sockaddr*>(&from), &from_size);
    if (n < 0 && errno == EINTR) continue;
    // An ICMP error (port unreachable from the peer whose socket is not yet open, or forged by
    // anyone) is reported once on a connected socket: no datagram; counted, and reading goes on.
    if (n < 0 && icmp_errno(errno)) {
      note_icmp(errno);
      continue;
    }
    if (n < 0) return false;
    d.received_ns = monotonic_ns();
    d.size = static_cast<std::size_t>(n);
    d.source_address = from.sin_addr.s_addr;
    d.source_port = from.sin_port;
    d.from_peer = from.sin_addr.s_addr == peer_address_ && from.sin_port == peer_port_;
    return true;
  }
}

}  // namespace rths::controller_node
