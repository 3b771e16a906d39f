// The view's server on loopback: pages from a fixed list, refusals counted, the stop button's
// rules, the control room's roles (presses and who may read the run), the event stream, a client that never reads, and a fresh client admitted beside idle,
// dripping and churning ones.
#include "view/server.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <deque>
#include <thread>

namespace rths::view {
namespace {

using namespace std::chrono_literals;

runtime::RecordEntry header() {
  runtime::RecordEntry e;
  e.mutable_header()->set_run_id("r");
  e.mutable_header()->set_dt(0.001);
  e.mutable_header()->set_actuators(1);
  return e;
}

runtime::RecordEntry step(std::int64_t k) {
  runtime::RecordEntry e;
  e.mutable_step()->set_step(k);
  e.mutable_step()->set_time(0.001 * static_cast<double>(k));
  e.mutable_step()->add_command(1e-3);
  e.mutable_step()->add_realised(1e-3);
  e.mutable_step()->add_measured_force(1);
  return e;
}

// Sends raw bytes and returns the whole answer (until the server closes or 2 s pass).
std::string raw_request(int port, const std::string& bytes) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) return "";
  timeval tv{2, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  (void)!write(fd, bytes.data(), bytes.size());
  std::string out;
  char buffer[4096];
  for (ssize_t n; (n = read(fd, buffer, sizeof buffer)) > 0;)
    out.append(buffer, static_cast<std::size_t>(n));
  close(fd);
  return out;
}

TEST(ListenAddress, ParsesHostAndPortAndRefusesTheRest) {
  const auto a = parse_listen_address("127.0.0.1:8080");
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 8080);
  EXPECT_TRUE(a.loopback());
  EXPECT_FALSE(parse_listen_address("0.0.0.0:80").loopback());
  EXPECT_TRUE(parse_listen_address("localhost:0").loopback());
  for (const char* bad : {"8080", ":8080", "127.0.0.1:", "127.0.0.1:70000", "127.0.0.1:8o",
                          "lab-pc:8080", "1.2.3:80"})
    EXPECT_THROW(parse_listen_address(bad), std::invalid_argument) << bad;
  try {
    parse_listen_address("127.0.0.1:70000");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--view 127.0.0.1:70000"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0-65535"), std::string::npos) << e.what();
  }
  EXPECT_EQ(make_token().size(), 32u);
  EXPECT_NE(make_token(), make_token());
}

TEST(ViewServer, ServesThePageFromAFixedListAndCountsWhatItRefuses) {
  Feed feed;
  ViewServer server(feed, {});
  httplib::Client client("127.0.0.1", server.port());
  auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/view.js"), std::string::npos);
  EXPECT_EQ(client.Get("/uPlot.iife.min.js")->status, 200);
  for (const char* path :
       {"/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/view.js/../../CMakeLists.txt",
        "/index.html", "/node_modules/uplot/package.json"}) {
    const auto r = client.Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, 404) << path;
    EXPECT_EQ(r->body.find("root:"), std::string::npos);
  }
  EXPECT_EQ(server.counters()["not_found"], 5);
  EXPECT_NE(raw_request(server.port(), "NONSENSE\r\n\r\n").find(" 400 "), std::string::npos);
  const std::string big(8192, 'x');
  EXPECT_EQ(client.Post("/api/stop", big, "text/plain")->status, 413);
  EXPECT_EQ(server.counters()["refused"], 2);
}

TEST(ViewServer, StopIsOffUnlessAskedAndThenNeedsItsToken) {
  Feed feed;
  std::atomic<int> stops{0};
  ServerOptions options;
  options.on_stop = [&] { ++stops; };
  {
    ViewServer off(feed, options);
    EXPECT_EQ(httplib::Client("127.0.0.1", off.port()).Post("/api/stop")->status, 403);
  }
  options.allow_stop = true;
  options.token = "0123456789abcdef0123456789abcdef";
  ViewServer server(feed, options);
  httplib::Client client("127.0.0.1", server.port());
  EXPECT_EQ(client.Post("/api/stop")->status, 403);
  EXPECT_EQ(
      client.Post("/api/stop", {{"X-RTHS-Token", "0123456789abcdef0123456789abcdee"}}, "", "")
          ->status,
      403);
  EXPECT_EQ(server.counters()["bad_token"], 2);
  EXPECT_EQ(stops, 0);
  EXPECT_EQ(client.Post("/api/stop", {{"X-RTHS-Token", options.token}}, "", "")->status, 202);
  EXPECT_EQ(client.Post("/api/stop", {{"X-RTHS-Token", options.token}}, "", "")->status, 202);
  EXPECT_EQ(stops, 1);  // once, however often it is pressed
  EXPECT_TRUE(server.stop_requested());
}

// With a control room the token's role decides: an operator's HOLD of their lab is 202, of
// another lab or a STOP 403 naming why; the director's STOP is 202; a token of no role is 403 and
// counted; /api/whoami names the role. Every press of a role is queued for the loop.
TEST(ViewServer, TheControlRoomAnswersEachRoleAsTheDeskJudgesIt) {
  Feed feed;
  ControlDesk desk(Crew::make({"lab_b", "lab_c"}), {{"lab_b", {2}}, {"lab_c", {3}}});
  ServerOptions options;
  options.desk = &desk;
  ViewServer server(feed, options);
  httplib::Client client("127.0.0.1", server.port());
  const auto post = [&](const char* path, const std::string& token, const std::string& lab) {
    return client.Post(path, {{"X-RTHS-Token", token}, {"X-RTHS-Lab", lab}}, "", "");
  };
  const std::string op = desk.crew().operators.at("lab_b");
  const auto health = nlohmann::json::parse(client.Get("/api/health")->body);
  EXPECT_TRUE(health["roles"].get<bool>());
  EXPECT_EQ(health["labs"]["lab_c"], nlohmann::json::array({3}));
  EXPECT_EQ(nlohmann::json::parse(post("/api/whoami", op, "")->body)["lab"], "lab_b");
  EXPECT_EQ(post("/api/whoami", "0123456789abcdef0123456789abcdef", "")->status, 403);
  const auto other = post("/api/hold", op, "lab_c");
  EXPECT_EQ(other->status, 403);
  EXPECT_NE(other->body.find("may HOLD only lab_b's actuators"), std::string::npos) << other->body;
  EXPECT_EQ(post("/api/stop", op, "")->status, 403);
  EXPECT_EQ(post("/api/stop", desk.crew().viewer, "")->status, 403);
  EXPECT_FALSE(server.stop_requested());
  EXPECT_EQ(post("/api/hold", op, "lab_b")->status, 202);
  EXPECT_EQ(post("/api/stop", "", "")->status, 403);
  EXPECT_EQ(server.counters()["bad_token"], 2);
  EXPECT_EQ(post("/api/stop", desk.crew().director, "")->status, 202);
  EXPECT_TRUE(server.stop_requested());
  const auto presses = desk.take();
  ASSERT_EQ(presses.size(), 5u);
  EXPECT_EQ(presses[3].hold_nodes, std::vector<int>{2});
  EXPECT_EQ(presses[3].seen_step, -1);  // the feed had seen no step
  EXPECT_TRUE(presses[4].stop);
}

// With a control room the run's data is for its crew: the snapshot and the stream refuse a
// request without a token (401) or with a token of no role (403), counted; any role's token, a
// viewer's included, reads them whole; the page's files and health stay open; the viewer's presses
// are refused.
TEST(ViewServer, WithRolesTheRunsDataIsServedOnlyToARolesToken) {
  Feed feed;
  feed.add(header());
  feed.add(step(0));
  feed.finish();
  ControlDesk desk(Crew::make({"lab_b"}), {{"lab_b", {2}}});
  ServerOptions options;
  options.desk = &desk;
  ViewServer server(feed, options);
  httplib::Client client("127.0.0.1", server.port());
  const auto get = [&](const char* path, const std::string& token) {
    return token.empty() ? client.Get(path) : client.Get(path, {{"X-RTHS-Token", token}});
  };
  const std::string stranger = "0123456789abcdef0123456789abcdef";
  for (const char* path : {"/api/snapshot", "/api/stream"}) {
    const auto bare = get(path, "");
    ASSERT_TRUE(bare) << path;
    EXPECT_EQ(bare->status, 401) << path;
    EXPECT_NE(bare->body.find("send your role's token"), std::string::npos) << bare->body;
    EXPECT_EQ(bare->body.find("\"header\""), std::string::npos) << path;
    const auto wrong = get(path, stranger);
    EXPECT_EQ(wrong->status, 403) << path;
    EXPECT_EQ(wrong->body.find("\"header\""), std::string::npos) << path;
  }
  EXPECT_EQ(server.counters()["bad_token"], 4);
  EXPECT_EQ(server.counters()["streams_served"], 0);
  for (const std::string& token :
       {desk.crew().viewer, desk.crew().operators.at("lab_b"), desk.crew().director}) {
    const auto snapshot = get("/api/snapshot", token);
    ASSERT_EQ(snapshot->status, 200);
    EXPECT_EQ(nlohmann::json::parse(snapshot->body)["header"]["run_id"], "r");
    const auto stream = get("/api/stream", token);
    ASSERT_EQ(stream->status, 200);
    EXPECT_NE(stream->body.find("data: {"), std::string::npos);
  }
  EXPECT_EQ(get("/", "")->status, 200);
  EXPECT_EQ(get("/api/health", "")->status, 200);
  const auto viewer = [&](const char* path) {
    return client.Post(path, {{"X-RTHS-Token", desk.crew().viewer}}, "", "")->status;
  };
  EXPECT_EQ(viewer("/api/stop"), 403);
  EXPECT_EQ(viewer("/api/hold"), 403);
  EXPECT_FALSE(server.stop_requested());
  for (const Press& press : desk.take()) EXPECT_FALSE(press.allowed) << press.text();
}

// A socket made by a launcher (open_listener) is served as given, at its port, with the Host
// checks of the address named.
TEST(ViewServer, ServesAListeningSocketHandedToIt) {
  Feed feed;
  const int fd = open_listener(parse_listen_address("127.0.0.1:0"));
  const int port = bound_port(fd);
  ASSERT_GT(port, 0);
  ServerOptions options;
  options.listen_fd = fd;
  ViewServer server(feed, options);
  EXPECT_EQ(server.port(), port);
  httplib::Client client("127.0.0.1", port);
  EXPECT_EQ(client.Get("/api/health")->status, 200);
  EXPECT_EQ(client.Get("/api/health", {{"Host", "lab-pc:" + std::to_string(port)}})->status, 403);
  EXPECT_THROW(open_listener(parse_listen_address("127.0.0.1:" + std::to_string(port))),
               std::runtime_error);  // SO_REUSEADDR, never two listeners on one port
}

TEST(ViewServer, StreamsTheFeedAsEventsAndEndsAfterItFinished) {
  Feed feed;
  ViewServer server(feed, {});
  feed.add(header());
  std::thread run([&] {
    for (int k = 0; k < 300; ++k) {
      feed.add(step(k));
      std::this_thread::sleep_for(1ms);
    }
    feed.finish();
  });
  httplib::Client client("127.0.0.1", server.port());
  std::string body;
  int events = 0;
  const auto r = client.Get("/api/stream", [&](const char* data, std::size_t n) {
    body.append(data, n);
    return true;
  });
  run.join();
  ASSERT_TRUE(r);
  for (std::size_t at = 0; (at = body.find("data: ", at)) != std::string::npos; ++at) ++events;
  EXPECT_GE(events, 2);
  EXPECT_LE(events, 60);  // ~0.3 s of run at most 30 updates/s, plus the last
  std::size_t samples = 0;
  for (std::size_t at = 0; (at = body.find("data: ", at)) != std::string::npos;) {
    const auto end = body.find("\n\n", at);
    const auto j = nlohmann::json::parse(body.substr(at + 6, end - at - 6));
    if (j.contains("samples")) samples += j["samples"]["step"].size();
    at = end;
  }
  EXPECT_EQ(samples, 30u);  // steps 0, 10, ..., 290, each once
  EXPECT_EQ(server.counters()["streams_served"], 1);
}

TEST(ViewServer, AClientThatNeverReadsIsDroppedAndCountedAndTheFeedNeverWaits) {
  FeedOptions every_step;
  every_step.points_per_second = 1000;  // large updates, so that the socket's buffers fill soon
  Feed feed(every_step);
  ServerOptions options;
  options.write_timeout = 300ms;
  ViewServer server(feed, options);
  feed.add(header());
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  int small = 1024;
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(server.port()));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  const std::string get =
      "GET /api/stream HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(server.port()) + "\r\n\r\n";
  ASSERT_EQ(write(fd, get.data(), get.size()), static_cast<ssize_t>(get.size()));
  const auto start = std::chrono::steady_clock::now();
  std::int64_t k = 0;
  while (server.counters()["streams_dropped"] == 0 &&
         std::chrono::steady_clock::now() - start < 20s)
    for (int i = 0; i < 2000; ++i) feed.add(step(k++));  // never blocks on the stuck client
  EXPECT_EQ(server.counters()["streams_dropped"], 1);
  close(fd);
  // The server still serves others.
  EXPECT_EQ(httplib::Client("127.0.0.1", server.port()).Get("/api/health")->status, 200);
}

TEST(ViewServer, RefusesStreamsBeyondItsLimit) {
  Feed feed;
  ServerOptions options;
  options.max_streams = 1;
  ViewServer server(feed, options);
  std::atomic<bool> first_open{false};
  std::thread first([&] {
    httplib::Client c("127.0.0.1", server.port());
    c.Get("/api/stream", [&](const char*, std::size_t) {
      first_open = true;
      return !server.stop_requested() && server.counters()["streams_refused"] == 0;
    });
  });
  while (!first_open) std::this_thread::sleep_for(5ms);
  EXPECT_EQ(httplib::Client("127.0.0.1", server.port()).Get("/api/stream")->status, 503);
  EXPECT_EQ(server.counters()["streams_refused"], 1);
  feed.finish();
  first.join();
}

// A socket connected to the view (-1 when it cannot connect).
int connect_to(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

TEST(ViewServer, IdleAndDrippingClientsLeaveThePageAndTheStopButtonReachable) {
  Feed feed;
  std::atomic<int> stops{0};
  ServerOptions options;
  options.allow_stop = true;
  options.on_stop = [&] { ++stops; };
  options.gate.header_deadline = 1000ms;
  ViewServer server(feed, options);
  std::vector<int> idle;
  for (int i = 0; i < 200; ++i) idle.push_back(connect_to(server.port()));
  // 8 clients that send one byte of a request every 2 s (each byte resets a per-read timeout).
  std::atomic<bool> done{false};
  std::vector<std::thread> drippers;
  for (int i = 0; i < 8; ++i)
    drippers.emplace_back([&] {
      const int fd = connect_to(server.port());
      const std::string request = "GET / HTTP/1.1\r\nHost: x\r\n\r\n";
      for (std::size_t at = 0; at < request.size() && !done; ++at) {
        if (send(fd, &request[at], 1, MSG_NOSIGNAL) != 1) break;
        for (int w = 0; w < 40 && !done; ++w) std::this_thread::sleep_for(50ms);
      }
      close(fd);
    });
  const auto admitted = [&] { return server.counters()["connections"]["connections"].get<int>(); };
  for (int i = 0; i < 1000 && admitted() < 208; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_EQ(admitted(), 208);  // the whole crowd is in before the fresh client comes
  httplib::Client fresh("127.0.0.1", server.port());
  fresh.set_connection_timeout(2s);
  fresh.set_read_timeout(2s);
  const auto page = fresh.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/view.js"), std::string::npos);
  const auto stop = fresh.Post("/api/stop", {{"X-RTHS-Token", server.token()}}, "", "");
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->status, 202);
  EXPECT_EQ(stops, 1);
  // The crowd is let go: the oldest idle ones at once (64 wait at most; the fresh client's first
  // connection made room for itself, its second found the room the first left), the rest and
  // the drippers at the deadline; only the fresh client's two requests were served.
  const nlohmann::json let_go = server.counters()["connections"];
  EXPECT_GE(let_go["evicted_idle"].get<int>() + let_go["header_timeouts"].get<int>(),
            200 + 8 + 1 - 64);
  for (int i = 0; i < 300 && server.counters()["connections"]["waiting"] > 0; ++i)
    std::this_thread::sleep_for(10ms);
  const nlohmann::json c = server.counters()["connections"];
  EXPECT_EQ(c["waiting"], 0);
  EXPECT_EQ(c["requests_served"], 2);
  EXPECT_EQ(c["evicted_idle"].get<int>() + c["header_timeouts"].get<int>(), 208);
  done = true;
  for (auto& d : drippers) d.join();
  for (const int fd : idle) close(fd);
}

// 200 idle connections kept open: each one the view closes (displaced, or past its header
// deadline) is opened again at once, a storm of thousands of connections a second that never
// lets up (a gate that displaced the oldest waiting connection, whatever it held, lost a fresh
// client's request in it nearly every time). Runs until `done`.
void hold_idle_crowd(int port, const std::atomic<bool>& done) {
  std::vector<pollfd> crowd;
  for (int i = 0; i < 200; ++i) crowd.push_back({connect_to(port), POLLIN, 0});
  while (!done) {
    poll(crowd.data(), crowd.size(), 50);
    for (pollfd& c : crowd) {
      if (c.fd >= 0 && c.revents == 0) continue;
      close(c.fd);  // closed by the view (EOF, or a 408 before it)
      c.fd = connect_to(port);
      c.revents = 0;
    }
  }
  for (const pollfd& c : crowd) close(c.fd);
}

// 15 new connections a second, each held 1 s: every other one never sends a byte, the rest send
// a whole request (and never read the answer).
void churn(int port, const std::atomic<bool>& done) {
  std::deque<int> open;
  const std::string request =
      "GET /api/health HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n";
  for (int k = 0; !done; ++k) {
    const int fd = connect_to(port);
    if (fd >= 0 && k % 2 == 1) (void)!send(fd, request.data(), request.size(), MSG_NOSIGNAL);
    open.push_back(fd);
    if (open.size() > 15) {
      close(open.front());
      open.pop_front();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1000 / 15));
  }
  for (const int fd : open) close(fd);
}

TEST(ViewServer, AFreshClientIsServedBesideAChurningClientAndAnIdleCrowdThatReopens) {
  Feed feed;
  ViewServer server(feed, {});
  std::atomic<bool> done{false};
  std::thread crowd([&] { hold_idle_crowd(server.port(), done); });
  std::thread churner([&] { churn(server.port(), done); });
  std::this_thread::sleep_for(1s);  // the crowd in, the first idle ones displaced and reopened
  int served = 0;
  std::vector<double> waits_ms;
  for (int attempt = 0; attempt < 20; ++attempt) {
    const auto start = std::chrono::steady_clock::now();
    httplib::Client fresh("127.0.0.1", server.port());
    fresh.set_connection_timeout(2s);
    fresh.set_read_timeout(2s);
    const auto page = fresh.Get("/");
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    waits_ms.push_back(ms);
    if (page && page->status == 200 && ms <= 2000) ++served;
    std::this_thread::sleep_for(100ms);
  }
  const nlohmann::json c = server.counters()["connections"];
  done = true;
  crowd.join();
  churner.join();
  std::string waits;
  for (const double ms : waits_ms) waits += std::to_string(static_cast<int>(ms)) + " ";
  EXPECT_EQ(served, 20) << "ms per try: " << waits << "; connections " << c.dump();
  EXPECT_GT(c["evicted_idle"].get<int>(), 200) << c.dump();  // the crowd did press on the door
}

TEST(ViewServer, ClientsLoopingOnTheSnapshotBuildItAtMostOncePerPeriod) {
  Feed feed;
  feed.add(header());
  for (int k = 0; k < 2000; ++k) feed.add(step(k));
  ServerOptions options;
  options.snapshot_period = 100ms;
  ViewServer server(feed, options);
  const auto start = std::chrono::steady_clock::now();
  std::atomic<int> answers{0};
  std::vector<std::thread> clients;
  for (int t = 0; t < 4; ++t)
    clients.emplace_back([&] {
      httplib::Client client("127.0.0.1", server.port());
      while (std::chrono::steady_clock::now() - start < 600ms) {
        const auto r = client.Get("/api/snapshot");
        ASSERT_TRUE(r);
        ASSERT_EQ(r->status, 200);
        const auto j = nlohmann::json::parse(r->body);
        ASSERT_EQ(j["samples"]["step"].size(), 200u);
        ++answers;
      }
    });
  for (auto& c : clients) c.join();
  const double elapsed_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const auto builds = server.counters()["snapshot_builds"].get<double>();
  EXPECT_LE(builds, elapsed_ms / 100.0 + 1.0);
  EXPECT_EQ(server.counters()["snapshots_served"], answers.load());
  EXPECT_GT(answers.load(), 4 * builds);
}

}  // namespace
}  // namespace rths::view
