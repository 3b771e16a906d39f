#pragma once
// The live view's HTTP server (cpp-httplib, Debian's libcpp-httplib-dev): the page and a
// server-sent-events stream of a Feed, on threads of its own (never the loop's).
//
//   GET  /, /view.js, /view.css, /uPlot.iife.min.js, /uPlot.min.css
//                      the page; read into memory at start, served from a fixed list (no path is
//                      ever mapped to the file system: anything else is 404, counted)
//   GET  /api/stream   text/event-stream: first everything the feed holds, then what is new, at
//                      most once per update_period (30 updates/s), each `data: {json}`; ends after
//                      the feed finished and its last state went out. At most max_streams at once
//                      (more: 503, counted). A client that does not read for write_timeout is
//                      dropped and counted; the feed never waits for a client.
//   GET  /api/snapshot everything the feed holds, as one JSON (scripts, tests): one copy shared
//                      by every client, rebuilt at most once per snapshot_period (SnapshotCache),
//                      so clients looping on it cannot take the feed's lock more often than that
//   GET  /api/health   the counters below and the options the page needs (stop enabled, mode)
//   POST /api/stop     only when allow_stop: calls on_stop once ("HOLD then STOP" is the caller's);
//                      with a token, the request must carry it (header X-RTHS-Token); else 403.
// Bad input: a malformed request line or header, a body over 4 KiB, an unknown path or method is
// refused (4xx) and counted; none of it touches the feed.
// Connections: a RequestGate (view/request_gate.h) holds each until its whole request has arrived
// (header deadline, idle connections beyond its limit closed oldest first); only then does one of
// max_streams + 4 threads serve it, one request per connection. Idle or dripping clients
// therefore never hold the threads that serve the page and the stop button.

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "view/feed.h"
#include "view/request_gate.h"
#include "view/snapshot_cache.h"

namespace httplib {
class Server;
}

namespace rths::view {

// "HOST:PORT" as given to --view: HOST an IPv4 address or "localhost", PORT 0-65535 (0 = any free).
struct ListenAddress {
  std::string host;
  int port = 0;
  bool loopback() const;  // 127.0.0.0/8 or localhost
};
// Throws std::invalid_argument naming `flag`, the value and what is allowed.
ListenAddress parse_listen_address(const std::string& text, const std::string& flag = "--view");

// 32 hex digits from the system's random source.
std::string make_token();

struct ServerOptions {
  ListenAddress address{"127.0.0.1", 0};
  std::filesystem::path web_dir;    // index.html, view.js, view.css; empty: the built-in default
  std::filesystem::path uplot_dir;  // uPlot.iife.min.js, uPlot.min.css; empty: the build's npm copy
  std::string mode = "live";        // "live" (a running test) or "replay" (a finished record)
  bool allow_stop = false;
  std::string token;  // required by /api/stop when non-empty
  std::function<void()> on_stop;
  int max_streams = 4;
  std::chrono::milliseconds update_period{33};
  std::chrono::milliseconds write_timeout{1000};
  std::chrono::milliseconds snapshot_period{200};  // /api/snapshot rebuilt at most this often
  GateOptions gate;  // its workers: max_streams + 4, whatever is set here
};

class ViewServer {
 public:
  // Loads the page's files and starts listening. Throws std::runtime_error naming the file or
  // the address when it cannot.
  ViewServer(const Feed& feed, ServerOptions options);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  int port() const { return port_; }
  std::string url() const;
  nlohmann::json counters() const;
  bool stop_requested() const { return stop_requested_.load(); }
  // Gives open streams up to `linger` to send the feed's last state, then stops.
  void shutdown(std::chrono::milliseconds linger = std::chrono::milliseconds(1000));

 private:
  void routes();
  void stream(httplib::Server& server);
  const Feed& feed_;
  ServerOptions options_;
  std::map<std::string, std::pair<std::string, std::string>> files_;  // path -> (type, bytes)
  std::unique_ptr<httplib::Server> server_;
  std::unique_ptr<RequestGate> gate_;  // after server_: stopped and destroyed before it
  std::unique_ptr<SnapshotCache> snapshots_;
  std::thread thread_;
  int port_ = 0;
  std::atomic<bool> stopping_{false}, stop_requested_{false};
  std::atomic<int> streams_{0};
  std::atomic<std::uint64_t> refused_{0}, not_found_{0}, bad_token_{0}, streams_refused_{0},
      streams_dropped_{0}, streams_served_{0}, updates_sent_{0}, stop_requests_{0};
};

}  // namespace rths::view
