#pragma once
// The live view's HTTP server (cpp-httplib, Debian's libcpp-httplib-dev): the page and a
// server-sent-events stream of a Feed, on threads of its own (never the loop's).
//
//   GET  /, /view.js, /sites.js, /view.css, /uPlot.iife.min.js, /uPlot.min.css
//                      the page; read into memory at start, served from a fixed list (no path is
//                      ever mapped to the file system: anything else is 404, counted)
// With a control room (desk) the run's data, /api/stream and /api/snapshot, is for its crew only:
// X-RTHS-Token must be a role's token (any role; a viewer sees everything), else 401 when it is
// missing, 403 when it is no role's, counted bad_token. The page's files and /api/health (whether
// roles are on, the counters) stay open: the page reads them before it knows its role.
//   GET  /api/stream   text/event-stream: first everything the feed holds, then what is new, at
//                      most once per update_period (30 updates/s), each `data: {json}`; ends after
//                      the feed finished and its last state went out. At most max_streams at once
//                      (more: 503, counted). A client that does not read for write_timeout is
//                      dropped and counted; the feed never waits for a client.
//   GET  /api/snapshot everything the feed holds, as one JSON (scripts, tests): one copy shared
//                      by every client, rebuilt at most once per snapshot_period and no sooner
//                      than 20 times its last build's CPU time (SnapshotCache), so clients looping
//                      on it cannot take the feed's lock more often than that, nor more than 5 %
//                      of a CPU however long the run
//   ?run=a, ?run=b     on /api/snapshot and /api/stream: which run (a, the default: the feed; b:
//                      ServerOptions::second, when two runs are compared); any other 404
//   GET  /compare      comparing two runs only: both pages side by side under each run's
//                      E_peak and E_rms, read from GET /api/compare (ServerOptions::comparison)
//   GET  /api/health   the counters below and the options the page needs (stop enabled, mode)
//   POST /api/stop     with a control room (desk, view/control_room.h): the token's role decides
//                      (the director's: 202 and the run stops; an operator's or a viewer's: 403
//                      naming why, and the press is recorded); a token of no role is 403,
//                      counted bad_token. Without a desk: only when allow_stop, and only with the run's token in the X-RTHS-Token
//                      header (compared in constant time; else 403, counted bad_token): calls
//                      on_stop once ("HOLD then STOP" is the caller's). The token is always
//                      needed, loopback included: any web page the user visits may POST to
//                      127.0.0.1, but only the person handed page_url() knows the token.
//   POST /api/hold     with a desk only: X-RTHS-Lab names the lab ("" or absent: every lab); the
//                      director may HOLD any, an operator only their own lab (else 403, recorded)
//   POST /api/whoami   with a desk: the role of X-RTHS-Token ({"role", "lab"}), 403 for none
// Every request, before its route: the Host header must name the address served with its port
// (127.0.0.1, localhost, [::1], the bound host, or the address the connection reached when bound
// to 0.0.0.0); an Origin header, when sent, must be http:// and that same host:port. Else 403,
// counted (bad_host, cross_origin): a page of another origin, or a name of its own rebound to
// 127.0.0.1 (DNS rebinding), can neither read the run nor press stop. So the view answers to its
// address, never to a host name (http://lab-pc:8080/ is refused; http://10.0.0.5:8080/ is not).
// Bad input: a malformed request line or header, a body over 4 KiB, an unknown path or method is
// refused (4xx) and counted; none of it touches the feed.
// Listening: SO_REUSEADDR (a port whose last connections wait in TIME_WAIT can be bound at once)
// and never SO_REUSEPORT (which would let two views share a port, each answering some of its
// connections): a port another live view holds is refused.
// Connections: a RequestGate (view/request_gate.h) holds each until its whole request has arrived
// (header deadline; beyond its limits the connection idle longest is closed, never one whose
// request has begun, and one address displaces only its own); only then does one of
// max_streams + 4 threads serve it, one request per connection. Idle, dripping or churning
// clients therefore never hold the threads that serve the page and the stop button.

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "view/control_room.h"
#include "view/feed.h"
#include "view/request_gate.h"
#include "view/snapshot_cache.h"

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace rths::view {

// "HOST:PORT" as given to --view: HOST an IPv4 address or "localhost", PORT 0-65535 (0 = any free).
struct ListenAddress {
  std::string host;
  int port = 0;
  bool loopback() const;  // 127.0.0.0/8 or localhost
};
// Throws std::invalid_argument naming `flag`, the value and what is allowed.
ListenAddress parse_listen_address(const std::string& text, const std::string& flag = "--view");

// make_token: view/control_room.h.

// A TCP socket bound to `address` and listening, without close-on-exec: a launcher makes it in
// its own network namespace and a program it starts (in another namespace, e.g. `ip netns exec`)
// serves it (ServerOptions::listen_fd), so a coordinator inside a site's namespace answers on
// the host's address. Throws std::runtime_error naming the address when it cannot.
int open_listener(const ListenAddress& address);
// The port a bound IPv4 socket has, -1 when it is not one.
int bound_port(int fd);

struct ServerOptions {
  ListenAddress address{"127.0.0.1", 0};
  std::filesystem::path web_dir;    // index.html, view.js, view.css; empty: the built-in default
  std::filesystem::path uplot_dir;  // uPlot.iife.min.js, uPlot.min.css; empty: the build's npm copy
  std::string mode = "live";        // "live" (a running test) or "replay" (a finished record)
  bool allow_stop = false;
  std::string token;  // what /api/stop needs; empty with allow_stop: one made here (make_token)
  std::function<void()> on_stop;
  ControlDesk* desk = nullptr;  // roles (view/control_room.h): stop, hold and whoami ask it
  // Two runs compared (a replay): the second run's feed (?run=b) and both runs' summaries, served
  // as /api/compare; null: one run.
  const Feed* second = nullptr;
  nlohmann::json comparison;
  // A listening socket to serve (open_listener) instead of binding `address`, whose host the
  // Host checks still name; -1: bind `address`. The server owns it from then on.
  int listen_fd = -1;
  int max_streams = 4;
  std::chrono::milliseconds update_period{33};
  std::chrono::milliseconds write_timeout{1000};
  std::chrono::milliseconds snapshot_period{200};  // /api/snapshot rebuilt at most this often
  GateOptions gate;  // its workers: max_streams + 4, whatever is set here
  // How long to keep trying an address that is in use (every 50 ms): a port a process that just
  // exited listened on (a coordinator's live view, which `rths launch` takes over) may be held
  // for a moment. 0: one try.
  std::chrono::milliseconds bind_for{0};
};

class ViewServer {
 public:
  // Loads the page's files and starts listening. Throws std::runtime_error naming the file or
  // the address when it cannot, std::invalid_argument for a stop token under 16 characters.
  ViewServer(const Feed& feed, ServerOptions options);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  int port() const { return port_; }
  std::string url() const;  // http://HOST:PORT/
  // What to open: url(), and with allow_stop its "?token=..." (the page sends it with a stop).
  std::string page_url() const;
  const std::string& token() const { return options_.token; }
  nlohmann::json counters() const;
  bool stop_requested() const { return stop_requested_.load(); }
  // Gives open streams up to `linger` to send the feed's last state, then stops.
  void shutdown(std::chrono::milliseconds linger = std::chrono::milliseconds(1000));

 private:
  void routes();
  void data_routes(httplib::Server& server);
  // The feed a data request names (?run=), or null with the 404 set.
  const Feed* feed_named(const httplib::Request& req, httplib::Response& res) const;
  void control_routes(httplib::Server& server);
  void control(const httplib::Request& req, httplib::Response& res, const std::string& action);
  // Whether the request may read the run's data: always without a desk; with one, only with a
  // role's token (else the 401 / 403 answer is set and counted).
  bool admitted(const httplib::Request& req, httplib::Response& res);
  void stop_listening();
  // Why a request is not for this server (its Host or Origin), or empty when it is.
  std::string foreign(const std::string& host, const std::string& origin,
                      const std::string& local_address);
  const Feed& feed_;
  ServerOptions options_;
  std::map<std::string, std::pair<std::string, std::string>> files_;  // path -> (type, bytes)
  std::unique_ptr<httplib::Server> server_;
  std::unique_ptr<RequestGate> gate_;  // after server_: stopped and destroyed before it
  std::unique_ptr<SnapshotCache> snapshots_, second_snapshots_;  // of the feed, of `second`
  std::thread thread_;
  int port_ = 0;
  std::atomic<bool> stopping_{false}, stop_requested_{false};
  std::atomic<bool> listen_returned_{false};  // set by thread_ when httplib's loop has ended
  std::atomic<int> streams_{0};
  std::atomic<std::uint64_t> refused_{0}, not_found_{0}, bad_token_{0}, bad_host_{0},
      cross_origin_{0}, streams_refused_{0}, streams_dropped_{0}, streams_served_{0},
      updates_sent_{0}, stop_requests_{0};
};

}  // namespace rths::view
