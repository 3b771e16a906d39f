#include "view/request_gate.h"

#include <netinet/in.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <strings.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>

namespace rths::view {
namespace {

// A short answer written without waiting (the socket's buffer holds it), then the close.
void answer_and_close(int fd, std::string_view status_line) {
  const std::string text = std::string("HTTP/1.1 ") + std::string(status_line) +
                           "\r\nConnection: close\r\nContent-Length: 0\r\n\r\n";
  (void)!send(fd, text.data(), text.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  close(fd);
}

// The Content-Length of a header block (0 when absent or unreadable: the server refuses those).
std::size_t content_length(std::string_view headers) {
  constexpr std::string_view kName = "\r\ncontent-length:";
  for (std::size_t at = 0; at + kName.size() <= headers.size(); ++at)
    if (strncasecmp(headers.data() + at, kName.data(), kName.size()) == 0)
      return static_cast<std::size_t>(
          std::strtoull(std::string(headers.substr(at + kName.size(), 20)).c_str(), nullptr, 10));
  return 0;
}

// The peer's IPv4 address (host order); 0 for anything else (one bucket for those).
std::uint32_t peer_address(int fd) {
  sockaddr_in peer{};
  socklen_t length = sizeof peer;
  if (getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &length) != 0 ||
      peer.sin_family != AF_INET)
    return 0;
  return ntohl(peer.sin_addr.s_addr);
}

}  // namespace

bool set_thread_nice(int nice) {
  return setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), nice) == 0;
}

bool enter_view_thread(const char* name, int nice) {
  std::string refused;  // each step the kernel refused, with its errno
  const auto note = [&refused](const std::string& step, int error) {
    refused += (refused.empty() ? "" : "; ") + step + " (errno " + std::to_string(error) + ", " +
               std::system_category().message(error) + ")";
  };
  if (const int error = pthread_setname_np(pthread_self(), name); error != 0)
    note("its name", error);
  const sched_param ordinary{};  // SCHED_OTHER takes priority 0
  // Leaving a real-time policy needs no privilege; pid 0 is the calling thread on Linux.
  if (sched_setscheduler(0, SCHED_OTHER, &ordinary) != 0) note("SCHED_OTHER", errno);
  if (!set_thread_nice(nice)) note("nice " + std::to_string(nice), errno);
  if (refused.empty()) return true;
  // Once per thread, as it starts: a view thread left at the loop's priority competes with it.
  spdlog::warn("view thread {} may serve at its creator's priority: the kernel refused {}", name,
               refused);
  return false;
}

RequestGate::RequestGate(GateOptions options, std::function<void(int fd)> serve)
    : options_(options),
      serve_(std::move(serve)),
      epoll_(epoll_create1(EPOLL_CLOEXEC)),
      waiting_({options.max_waiting, options.max_per_address}) {
  if (epoll_ < 0) throw std::runtime_error("the view cannot create its epoll set");
  poller_ = std::thread([this] {
    enter_view_thread("view-gate", options_.nice);
    poll_loop();
  });
  for (int i = 0; i < options_.workers; ++i)
    workers_.emplace_back([this] {
      enter_view_thread("view-serve", options_.nice);
      worker_loop();
    });
}

RequestGate::~RequestGate() { stop(); }

void RequestGate::admit(int fd) {
  std::vector<std::pair<int, Peek>> found;
  {
    std::lock_guard lock(mutex_);
    if (stopping_) {
      close(fd);
      return;
    }
    ++admitted_;
    const std::uint32_t address = peer_address(fd);
    make_room(address, found);
    waiting_.add(fd, address, std::chrono::steady_clock::now());
    // Edge-triggered: woken when bytes arrive (and once at once if some already have).
    epoll_event event{};
    event.events = EPOLLIN | EPOLLRDHUP | EPOLLET;
    event.data.fd = fd;
    epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &event);
  }
  for (const auto& [ready, state] : found) finish(ready, state);
}

void RequestGate::make_room(std::uint32_t address, std::vector<std::pair<int, Peek>>& found) {
  const auto now = std::chrono::steady_clock::now();
  // Each pass displaces one, finds one gone from the table, or learns of new bytes in one (which
  // then ranks after every idle one); the bound only guards against bytes arriving without end.
  for (std::size_t pass = 0; pass <= options_.max_waiting + 1; ++pass) {
    const std::optional<int> victim = waiting_.displaced_by(address);
    if (!victim) return;
    const Peeked seen = peek(*victim);
    if (seen.state != Peek::kIncomplete) {
      forget(*victim);
      found.emplace_back(*victim, seen.state);
      continue;
    }
    if (waiting_.saw_bytes(*victim, seen.bytes, now) && pass <= options_.max_waiting) continue;
    forget(*victim);
    close(*victim);
    ++evicted_;
  }
}

void RequestGate::forget(int fd) {
  if (!waiting_.remove(fd)) return;
  epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
}

RequestGate::Peeked RequestGate::peek(int fd) const {
  char first = 0;  // an idle socket (the common case when displacing) costs no buffer
  const ssize_t any = recv(fd, &first, 1, MSG_PEEK | MSG_DONTWAIT);
  if (any < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return {Peek::kIncomplete, 0};
  std::string buffer(options_.max_request_bytes, '\0');
  const ssize_t n = recv(fd, buffer.data(), buffer.size(), MSG_PEEK | MSG_DONTWAIT);
  if (n == 0) return {Peek::kClosed, 0};
  if (n < 0)
    return {(errno == EAGAIN || errno == EWOULDBLOCK) ? Peek::kIncomplete : Peek::kClosed, 0};
  const std::string_view got(buffer.data(), static_cast<std::size_t>(n));
  const auto end = got.find("\r\n\r\n");
  if (end == std::string_view::npos)
    return {got.size() >= options_.max_request_bytes ? Peek::kTooLarge : Peek::kIncomplete,
            got.size()};
  const std::size_t body = content_length(got.substr(0, end + 2));
  // A body larger than the buffer is the server's to refuse (413) at once, unread.
  if (end + 4 + body > options_.max_request_bytes) return {Peek::kComplete, got.size()};
  return {got.size() >= end + 4 + body ? Peek::kComplete : Peek::kIncomplete, got.size()};
}

void RequestGate::on_readable(int fd) {
  Peek state = Peek::kIncomplete;
  {
    // Under the lock, so that an fd evicted and reused meanwhile is judged by its own bytes.
    std::lock_guard lock(mutex_);
    if (!waiting_.contains(fd)) return;  // evicted or expired meanwhile
    const Peeked seen = peek(fd);
    state = seen.state;
    if (state == Peek::kIncomplete) {
      waiting_.saw_bytes(fd, seen.bytes, std::chrono::steady_clock::now());
      return;
    }
    forget(fd);
  }
  finish(fd, state);
}

void RequestGate::finish(int fd, Peek state) {
  if (state == Peek::kComplete) {
    enqueue(fd);
    return;
  }
  {
    std::lock_guard lock(mutex_);
    ++(state == Peek::kTooLarge ? too_large_ : closed_early_);
  }
  if (state == Peek::kTooLarge)
    answer_and_close(fd, "431 Request Header Fields Too Large");
  else
    close(fd);
}

void RequestGate::expire(std::chrono::steady_clock::time_point now) {
  std::vector<int> late;
  {
    std::lock_guard lock(mutex_);
    late = waiting_.take_arrived_by(now - options_.header_deadline);
    for (const int fd : late) epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
    timed_out_ += late.size();
  }
  for (const int fd : late) answer_and_close(fd, "408 Request Timeout");
}

void RequestGate::poll_loop() {
  std::vector<epoll_event> events(64);
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
    }
    const int n = epoll_wait(epoll_, events.data(), static_cast<int>(events.size()), 20);
    for (int i = 0; i < n; ++i) on_readable(events[static_cast<std::size_t>(i)].data.fd);
    expire(std::chrono::steady_clock::now());
  }
}

void RequestGate::enqueue(int fd) {
  {
    std::lock_guard lock(mutex_);
    if (!stopping_ && queue_.size() < options_.max_queued) {
      queue_.push_back(fd);
      queued_cv_.notify_one();
      return;
    }
    ++queue_full_;
  }
  answer_and_close(fd, "503 Service Unavailable");
}

void RequestGate::worker_loop() {
  for (;;) {
    int fd = -1;
    {
      std::unique_lock lock(mutex_);
      queued_cv_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      fd = queue_.front();
      queue_.pop_front();
      ++served_;
    }
    serve_(fd);
    shutdown(fd, SHUT_RDWR);
    close(fd);
  }
}

void RequestGate::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
    for (const int fd : waiting_.fds()) {
      waiting_.remove(fd);
      close(fd);
    }
    for (const int fd : queue_) close(fd);
    queue_.clear();
  }
  queued_cv_.notify_all();
  if (poller_.joinable()) poller_.join();
  for (auto& w : workers_)
    if (w.joinable()) w.join();
  close(epoll_);
}

nlohmann::json RequestGate::counters() const {
  std::lock_guard lock(mutex_);
  return {{"connections", admitted_},      {"requests_served", served_},
          {"header_timeouts", timed_out_}, {"evicted_idle", evicted_},
          {"too_large", too_large_},       {"closed_early", closed_early_},
          {"queue_full", queue_full_},     {"waiting", waiting_.size()}};
}

}  // namespace rths::view
