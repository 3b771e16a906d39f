#include "opensees_site/tcp_channel.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include <spdlog/spdlog.h>

namespace rths::opensees {

namespace {

using Clock = std::chrono::steady_clock;

std::string peer_of(const sockaddr_in& a) {
  char text[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &a.sin_addr, text, sizeof text);
  return std::string(text) + ":" + std::to_string(ntohs(a.sin_port));
}

// ms to wait in poll(): -1 without a deadline, else what is left (at least 0).
int poll_ms(std::optional<Clock::time_point> deadline) {
  if (!deadline) return -1;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - Clock::now());
  return left.count() <= 0 ? 0 : static_cast<int>(left.count()) + 1;
}

}  // namespace

bool is_loopback(const std::string& address) {
  in_addr a{};
  return inet_pton(AF_INET, address.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

Connection::Connection(int fd, std::string peer, Listener* listener)
    : fd_(fd), peer_(std::move(peer)), listener_(listener) {}

Connection::Connection(Connection&& other) noexcept
    : fd_(other.fd_),
      peer_(std::move(other.peer_)),
      listener_(other.listener_),
      send_timeout_seconds_(other.send_timeout_seconds_) {
  other.fd_ = -1;
}

Connection::~Connection() {
  if (fd_ >= 0) ::close(fd_);
}

void Connection::end() {
  if (fd_ >= 0) ::shutdown(fd_, SHUT_RDWR);
}

Connection::ReadResult Connection::read_exact(void* data, std::size_t size,
                                              std::chrono::nanoseconds timeout) {
  auto* out = static_cast<char*>(data);
  ReadResult r;
  const auto deadline =
      timeout.count() < 0
          ? std::nullopt
          : std::optional(Clock::now() + std::chrono::duration_cast<Clock::duration>(timeout));
  while (r.bytes < size) {
    pollfd fds[2] = {{fd_, POLLIN, 0}, {listener_ ? listener_->fd() : -1, POLLIN, 0}};
    const int ready = ::poll(fds, listener_ ? 2 : 1, poll_ms(deadline));
    if (ready < 0 && errno == EINTR) continue;
    if (listener_ && (fds[1].revents & POLLIN))
      listener_->refuse_waiting("one OpenSees client at a time; " + peer_ + " is being served");
    if (fds[0].revents & (POLLIN | POLLHUP | POLLERR)) {
      const ssize_t got = ::recv(fd_, out + r.bytes, size - r.bytes, 0);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        r.status = r.bytes == 0 ? Read::kClosed : Read::kTruncated;
        return r;
      }
      r.bytes += static_cast<std::size_t>(got);
      // genericClient leaves Nagle on (TCP_Socket's noDelay 0): its next frame waits for our ACK
      // of this one, which a delayed ACK holds back 40 ms when we do not answer (setTrialResponse).
      // Quick ACKs (reset by the kernel, so set after every read) keep a step to a round trip.
      const int one = 1;
      ::setsockopt(fd_, IPPROTO_TCP, TCP_QUICKACK, &one, sizeof one);
      continue;
    }
    if (deadline && Clock::now() >= *deadline) {
      r.status = Read::kTimedOut;
      return r;
    }
  }
  return r;
}

void Connection::write_all(const void* data, std::size_t size) {
  const auto* in = static_cast<const char*>(data);
  std::size_t sent = 0;
  while (sent < size) {
    const ssize_t n = ::send(fd_, in + sent, size - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      std::string why = "the OpenSees client ";
      why += peer_;
      why += " read nothing for the send timeout (";
      why += std::to_string(send_timeout_seconds_);
      why += " s): it stopped reading its answers";
      throw std::runtime_error(why);
    }
    if (n <= 0)
      throw std::runtime_error("cannot write to the OpenSees client " + peer_ + ": " +
                               std::strerror(errno));
    sent += static_cast<std::size_t>(n);
  }
}

void Connection::set_send_timeout(std::chrono::nanoseconds timeout) {
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(timeout).count();
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(us / 1'000'000);
  tv.tv_usec = static_cast<suseconds_t>(us % 1'000'000);
  ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  send_timeout_seconds_ = static_cast<double>(us) * 1e-6;
}

Listener::Listener(const std::string& address, int port) : address_(address) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1)
    throw std::invalid_argument("--listen: '" + address + "' is not an IPv4 address");
  if (port < 0 || port > 65535)
    throw std::invalid_argument("--port: " + std::to_string(port) + " is outside 0..65535");
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const int one = 1;
  if (fd_ < 0 || ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
      ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd_, 4) != 0) {
    const std::string why = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    throw std::runtime_error("cannot listen on " + address + ":" + std::to_string(port) + ": " +
                             why);
  }
  socklen_t length = sizeof a;
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &length);
  port_ = ntohs(a.sin_port);
}

Listener::~Listener() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<Connection> Listener::accept(std::chrono::milliseconds timeout) {
  pollfd fds{fd_, POLLIN, 0};
  const int ready = ::poll(&fds, 1, timeout.count() < 0 ? -1 : static_cast<int>(timeout.count()));
  if (ready <= 0) return std::nullopt;
  sockaddr_in a{};
  socklen_t length = sizeof a;
  const int fd = ::accept4(fd_, reinterpret_cast<sockaddr*>(&a), &length, SOCK_CLOEXEC);
  if (fd < 0) return std::nullopt;
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return Connection(fd, peer_of(a), this);
}

int Listener::refuse_waiting(const std::string& why) {
  int refused = 0;
  for (;;) {
    pollfd fds{fd_, POLLIN, 0};
    if (::poll(&fds, 1, 0) <= 0) return refused;
    sockaddr_in a{};
    socklen_t length = sizeof a;
    const int fd = ::accept4(fd_, reinterpret_cast<sockaddr*>(&a), &length, SOCK_CLOEXEC);
    if (fd < 0) return refused;
    spdlog::warn("refused the OpenSees client {}: {}", peer_of(a), why);
    ::close(fd);
    ++refused;
  }
}

}  // namespace rths::opensees
