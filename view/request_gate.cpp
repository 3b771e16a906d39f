#include "view/request_gate.h"

#include <strings.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <stdexcept>
#include <string_view>

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

}  // namespace

bool set_thread_nice(int nice) {
  return setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), nice) == 0;
}

RequestGate::RequestGate(GateOptions options, std::function<void(int fd)> serve)
    : options_(options), serve_(std::move(serve)), epoll_(epoll_create1(EPOLL_CLOEXEC)) {
  if (epoll_ < 0) throw std::runtime_error("the view cannot create its epoll set");
  poller_ = std::thread([this] {
    set_thread_nice(options_.nice);
    poll_loop();
  });
  for (int i = 0; i < options_.workers; ++i)
    workers_.emplace_back([this] {
      set_thread_nice(options_.nice);
      worker_loop();
    });
}

RequestGate::~RequestGate() { stop(); }

void RequestGate::admit(int fd) {
  std::lock_guard lock(mutex_);
  if (stopping_) {
    close(fd);
    return;
  }
  ++admitted_;
  if (waiting_.size() >= options_.max_waiting) {
    const int oldest = waiting_.front().fd;
    forget(oldest);
    close(oldest);
    ++evicted_;
  }
  waiting_.push_back({fd, std::chrono::steady_clock::now() + options_.header_deadline});
  waiting_at_[fd] = std::prev(waiting_.end());
  // Edge-triggered: woken when bytes arrive (and once at once if some already have).
  epoll_event event{};
  event.events = EPOLLIN | EPOLLRDHUP | EPOLLET;
  event.data.fd = fd;
  epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &event);
}

void RequestGate::forget(int fd) {
  const auto at = waiting_at_.find(fd);
  if (at == waiting_at_.end()) return;
  waiting_.erase(at->second);
  waiting_at_.erase(at);
  epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
}

RequestGate::Peek RequestGate::peek(int fd) const {
  std::string buffer(options_.max_request_bytes, '\0');
  const ssize_t n = recv(fd, buffer.data(), buffer.size(), MSG_PEEK | MSG_DONTWAIT);
  if (n == 0) return Peek::kClosed;
  if (n < 0) return (errno == EAGAIN || errno == EWOULDBLOCK) ? Peek::kIncomplete : Peek::kClosed;
  const std::string_view got(buffer.data(), static_cast<std::size_t>(n));
  const auto end = got.find("\r\n\r\n");
  if (end == std::string_view::npos)
    return got.size() >= options_.max_request_bytes ? Peek::kTooLarge : Peek::kIncomplete;
  const std::size_t body = content_length(got.substr(0, end + 2));
  // A body larger than the buffer is the server's to refuse (413) at once, unread.
  if (end + 4 + body > options_.max_request_bytes) return Peek::kComplete;
  return got.size() >= end + 4 + body ? Peek::kComplete : Peek::kIncomplete;
}

void RequestGate::on_readable(int fd) {
  Peek state = Peek::kIncomplete;
  {
    // Under the lock, so that an fd evicted and reused meanwhile is judged by its own bytes.
    std::lock_guard lock(mutex_);
    if (!waiting_at_.count(fd)) return;  // evicted or expired meanwhile
    state = peek(fd);
    if (state == Peek::kIncomplete) return;
    forget(fd);
    if (state == Peek::kClosed) ++closed_early_;
    if (state == Peek::kTooLarge) ++too_large_;
  }
  if (state == Peek::kClosed) close(fd);
  if (state == Peek::kTooLarge) answer_and_close(fd, "431 Request Header Fields Too Large");
  if (state == Peek::kComplete) enqueue(fd);
}

void RequestGate::expire(std::chrono::steady_clock::time_point now) {
  std::vector<int> late;
  {
    std::lock_guard lock(mutex_);
    while (!waiting_.empty() && waiting_.front().deadline <= now) {
      late.push_back(waiting_.front().fd);
      forget(late.back());
      ++timed_out_;
    }
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
    for (const auto& w : waiting_) close(w.fd);
    for (const int fd : queue_) close(fd);
    waiting_.clear();
    waiting_at_.clear();
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
