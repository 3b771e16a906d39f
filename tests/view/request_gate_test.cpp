// The view's front door on real loopback sockets: a request reaches a worker only once whole
// (headers and body), idle connections beyond the limit are closed oldest first, one whose
// request has begun is kept over idle ones, one address at its share displaces only its own, a
// connection that does not finish its request in time is closed, an oversized header block is
// refused; its threads are the view's own (named, SCHED_OTHER at its nice) whoever starts it,
// and warn when the kernel refuses a step of that.
#include "view/request_gate.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sched.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

namespace rths::view {
namespace {

using namespace std::chrono_literals;

// A listening socket on loopback and connected pairs from it: (client side, server side).
class Loopback {
 public:
  Loopback() {
    listener_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    bind(listener_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    listen(listener_, 512);
    socklen_t length = sizeof addr_;
    getsockname(listener_, reinterpret_cast<sockaddr*>(&addr_), &length);
  }
  ~Loopback() { close(listener_); }
  // `from`: the client's own loopback address (all of 127.0.0.0/8 is this host's).
  std::pair<int, int> pair(const char* from = "127.0.0.1") const {
    const int client = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    inet_pton(AF_INET, from, &local.sin_addr);
    bind(client, reinterpret_cast<sockaddr*>(&local), sizeof local);
    connect(client, reinterpret_cast<const sockaddr*>(&addr_), sizeof addr_);
    return {client, accept(listener_, nullptr, nullptr)};
  }

 private:
  int listener_ = -1;
  sockaddr_in addr_{};
};

void send_text(int fd, const std::string& text) {
  ASSERT_EQ(send(fd, text.data(), text.size(), MSG_NOSIGNAL), static_cast<ssize_t>(text.size()));
}

// Whether the server closed `fd` (read returns 0 or an answer, within 2 s).
std::string read_until_closed(int fd) {
  timeval tv{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string out;
  char buffer[512];
  for (ssize_t n; (n = read(fd, buffer, sizeof buffer)) > 0;)
    out.append(buffer, static_cast<std::size_t>(n));
  return out;
}

// Served requests: what the worker read from each socket (the whole request, as sent).
struct Served {
  std::mutex mutex;
  std::vector<std::string> requests;
  std::function<void(int)> serve() {
    return [this](int fd) {
      char buffer[16384];
      const ssize_t n = recv(fd, buffer, sizeof buffer, MSG_DONTWAIT);
      std::lock_guard lock(mutex);
      requests.emplace_back(buffer, n > 0 ? static_cast<std::size_t>(n) : 0);
    };
  }
  std::size_t count() {
    std::lock_guard lock(mutex);
    return requests.size();
  }
};

bool eventually(const std::function<bool()>& done) {
  for (int i = 0; i < 300 && !done(); ++i) std::this_thread::sleep_for(10ms);
  return done();
}

TEST(RequestGate, HandsOverARequestOnlyOnceItsHeadersAndBodyHaveArrived) {
  Loopback net;
  Served served;
  RequestGate gate({}, served.serve());
  const auto [client, server] = net.pair();
  gate.admit(server);
  send_text(client, "POST /api/stop HTTP/1.1\r\nHost: x\r\nContent-Length: 5\r\n\r\nab");
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(served.count(), 0u);  // the body is not all there
  send_text(client, "cde");
  ASSERT_TRUE(eventually([&] { return served.count() == 1; }));
  EXPECT_EQ(served.requests[0].substr(served.requests[0].size() - 5), "abcde");
  EXPECT_EQ(read_until_closed(client), "");  // closed by the gate after serve
  close(client);
  EXPECT_EQ(gate.counters()["requests_served"], 1);
}

TEST(RequestGate, ClosesTheOldestIdleConnectionsBeyondItsLimitAndServesAFreshOne) {
  Loopback net;
  Served served;
  GateOptions options;
  options.max_waiting = 8;
  RequestGate gate(options, served.serve());
  std::vector<int> idle;
  for (int i = 0; i < 40; ++i) {
    const auto [client, server] = net.pair();
    gate.admit(server);
    idle.push_back(client);
  }
  const auto [fresh, server] = net.pair();
  gate.admit(server);
  send_text(fresh, "GET / HTTP/1.1\r\nHost: x\r\n\r\n");
  ASSERT_TRUE(eventually([&] { return served.count() == 1; }));
  EXPECT_EQ(gate.counters()["evicted_idle"], 40 + 1 - 8);
  EXPECT_EQ(read_until_closed(idle.front()), "");  // the oldest were closed
  for (const int fd : idle) close(fd);
  close(fresh);
}

// Admitted one after another at once, faster than the epoll thread may see the first's bytes:
// the connection whose request has begun is displaced by none of them.
TEST(RequestGate, KeepsAConnectionWhoseRequestHasBegunOverIdleOnes) {
  Loopback net;
  Served served;
  GateOptions options;
  options.max_waiting = 4;
  RequestGate gate(options, served.serve());
  const auto [browser, server] = net.pair();
  send_text(browser, "GET / HTTP/1.1\r\nHo");  // the rest comes later
  gate.admit(server);
  std::vector<int> idle;
  for (int i = 0; i < 40; ++i) {
    const auto [client, accepted] = net.pair();
    gate.admit(accepted);
    idle.push_back(client);
  }
  EXPECT_EQ(gate.counters()["evicted_idle"], 40 + 1 - 4);
  send_text(browser, "st: x\r\n\r\n");
  ASSERT_TRUE(eventually([&] { return served.count() == 1; }));
  EXPECT_EQ(served.requests[0], "GET / HTTP/1.1\r\nHost: x\r\n\r\n");
  for (const int fd : idle) close(fd);
  close(browser);
}

TEST(RequestGate, OneAddressAtItsShareClosesOnlyItsOwnIdleConnections) {
  Loopback net;
  Served served;
  GateOptions options;
  options.max_waiting = 8;
  options.max_per_address = 6;
  RequestGate gate(options, served.serve());
  const auto [other, other_server] = net.pair("127.0.0.2");  // another host, idle the longest
  gate.admit(other_server);
  std::vector<int> crowd;
  for (int i = 0; i < 40; ++i) {
    const auto [client, accepted] = net.pair("127.0.0.1");
    gate.admit(accepted);
    crowd.push_back(client);
  }
  EXPECT_EQ(gate.counters()["evicted_idle"], 40 - 6);
  EXPECT_EQ(gate.counters()["waiting"], 1 + 6);  // the slot above the crowd's share stays free
  send_text(other, "GET / HTTP/1.1\r\nHost: x\r\n\r\n");
  ASSERT_TRUE(eventually([&] { return served.count() == 1; }));
  for (const int fd : crowd) close(fd);
  close(other);
}

TEST(RequestGate, ClosesAConnectionThatDripsItsHeadersPastTheDeadline) {
  Loopback net;
  Served served;
  GateOptions options;
  options.header_deadline = 300ms;
  RequestGate gate(options, served.serve());
  const auto [client, server] = net.pair();
  gate.admit(server);
  send_text(client, "GET / HTTP/1.1\r\n");
  std::this_thread::sleep_for(200ms);
  send_text(client, "Host: x\r\n");  // still no end of headers
  EXPECT_NE(read_until_closed(client).find(" 408 "), std::string::npos);
  EXPECT_EQ(served.count(), 0u);
  EXPECT_EQ(gate.counters()["header_timeouts"], 1);
  close(client);
}

TEST(RequestGate, RefusesAHeaderBlockLargerThanItsLimit) {
  Loopback net;
  Served served;
  RequestGate gate({}, served.serve());
  const auto [client, server] = net.pair();
  gate.admit(server);
  send_text(client, "GET / HTTP/1.1\r\nX-Long: " + std::string(13000, 'x'));
  EXPECT_NE(read_until_closed(client).find(" 431 "), std::string::npos);
  EXPECT_EQ(gate.counters()["too_large"], 1);
  EXPECT_EQ(served.count(), 0u);
  close(client);
}

// This process's threads named `name`: (scheduling policy, nice value) of each.
std::vector<std::pair<int, int>> threads_named(const std::string& name) {
  std::vector<std::pair<int, int>> found;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string seen;
    if (!std::getline(comm, seen) || seen != name) continue;
    const auto tid = static_cast<pid_t>(std::stol(task.path().filename().string()));
    errno = 0;
    const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(tid));
    if (errno == 0) found.emplace_back(sched_getscheduler(tid), nice);
  }
  return found;
}

// Started from a thread on SCHED_FIFO (a loop raised by realtime_priority; where this process may
// not raise one, SCHED_BATCH: either is inherited by new threads), the gate's threads still run
// as the view's own: named, on SCHED_OTHER, at the gate's nice value.
TEST(RequestGate, ItsThreadsAreNamedAndOrdinaryAtItsNiceWhateverTheCreatorRunsAt) {
  Served served;
  GateOptions options;
  options.workers = 3;
  options.nice = 12;
  std::unique_ptr<RequestGate> gate;
  int creator_policy = -1;
  std::thread creator([&] {
    const sched_param fifo{.sched_priority = 1}, none{};
    if (sched_setscheduler(0, SCHED_FIFO, &fifo) != 0) sched_setscheduler(0, SCHED_BATCH, &none);
    creator_policy = sched_getscheduler(0);
    gate = std::make_unique<RequestGate>(options, served.serve());
  });
  creator.join();
  ASSERT_TRUE(creator_policy == SCHED_FIFO || creator_policy == SCHED_BATCH);
  const std::pair<int, int> ordinary{SCHED_OTHER, 12};
  const std::vector<std::pair<int, int>> workers(3, ordinary), poller(1, ordinary);
  EXPECT_TRUE(eventually([&] { return threads_named("view-serve") == workers; }));
  EXPECT_EQ(threads_named("view-gate"), poller);
  gate->stop();
  EXPECT_TRUE(threads_named("view-serve").empty());
}

// A step the kernel refuses is not silent: a name past 15 characters (ERANGE, refused without any
// privilege) makes the thread warn once, naming itself and the errno, and answer false.
TEST(RequestGate, AThreadWhoseSetUpTheKernelRefusesWarnsNamingItselfAndTheErrno) {
  std::ostringstream log;
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>(
      "capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(log)));
  bool entered = true;
  std::thread([&] { entered = enter_view_thread("view-name-too-long-for-comm", 10); }).join();
  spdlog::set_default_logger(previous);
  EXPECT_FALSE(entered);
  const std::string text = log.str();
  EXPECT_NE(text.find("[warning]"), std::string::npos) << text;
  EXPECT_NE(text.find("view thread view-name-too-long-for-comm"), std::string::npos) << text;
  EXPECT_NE(text.find("its name (errno " + std::to_string(ERANGE)), std::string::npos) << text;
  EXPECT_EQ(text.find("SCHED_OTHER"), std::string::npos) << text;  // the other steps were done
}

}  // namespace
}  // namespace rths::view
