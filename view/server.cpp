#include "view/server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <httplib.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <vector>

#include "transport/transport.h"

#ifndef RTHS_VIEW_WEB_DIR
#error "RTHS_VIEW_WEB_DIR must name the page's source folder"
#endif
#ifndef RTHS_VIEW_UPLOT_DIR
#error "RTHS_VIEW_UPLOT_DIR must name uPlot's dist folder (npm, installed by the build)"
#endif

namespace rths::view {
namespace {

std::string read_whole(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error("the view's page file " + path.string() +
                             " is missing (build the rths_view_web target: it runs npm ci)");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Equal strings in a time that does not depend on where they differ.
bool same_token(const std::string& a, const std::string& b) {
  unsigned diff = a.size() == b.size() ? 0u : 1u;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
    diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// Whether a Host header's value (lower case) names one of `names` with `port` (a browser leaves
// out ":80" on port 80).
bool names_served(const std::string& host, const std::vector<std::string>& names, int port) {
  for (const std::string& name : names) {
    if (name.empty()) continue;
    if (host == name + ":" + std::to_string(port) || (port == 80 && host == name)) return true;
  }
  return false;
}

// One connection's socket as httplib's Stream: non-blocking, each read and write waiting at most
// its timeout for the socket to be ready; reads buffered (httplib reads a request line by byte).
class FdStream : public httplib::Stream {
 public:
  FdStream(int fd, int read_ms, int write_ms) : fd_(fd), read_ms_(read_ms), write_ms_(write_ms) {
    fcntl(fd_, F_SETFL, fcntl(fd_, F_GETFL) | O_NONBLOCK);
  }
  bool is_readable() const override { return at_ < got_ || ready(POLLIN, read_ms_); }
  bool is_writable() const override { return ready(POLLOUT, write_ms_); }
  ssize_t read(char* out, std::size_t size) override {
    if (at_ == got_) {
      if (!ready(POLLIN, read_ms_)) return -1;
      const ssize_t n = recv(fd_, buffer_, sizeof buffer_, 0);
      if (n <= 0) return n;
      at_ = 0;
      got_ = static_cast<std::size_t>(n);
    }
    const std::size_t n = std::min(size, got_ - at_);
    std::copy(buffer_ + at_, buffer_ + at_ + n, out);
    at_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* data, std::size_t size) override {
    if (!ready(POLLOUT, write_ms_)) return -1;
    return send(fd_, data, size, MSG_NOSIGNAL);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    address(getpeername, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    address(getsockname, ip, port);
  }
  ::socket_t socket() const override { return fd_; }

 private:
  bool ready(short events, int ms) const {
    pollfd p{fd_, events, 0};
    return poll(&p, 1, ms) > 0 && (p.revents & events) != 0;
  }
  void address(int (*get)(int, sockaddr*, socklen_t*), std::string& ip, int& port) const {
    sockaddr_in a{};
    socklen_t length = sizeof a;
    char text[INET_ADDRSTRLEN] = "";
    if (get(fd_, reinterpret_cast<sockaddr*>(&a), &length) == 0 && a.sin_family == AF_INET)
      inet_ntop(AF_INET, &a.sin_addr, text, sizeof text);
    ip = text;
    port = ntohs(a.sin_port);
  }
  int fd_, read_ms_, write_ms_;
  char buffer_[4096];
  std::size_t at_ = 0, got_ = 0;
};

// httplib's accepting thread hands each connection to the task queue; this one runs the hand-off
// at once, and the hand-off (process_and_close_socket) gives the socket to the RequestGate.
struct HandOver : httplib::TaskQueue {
  void enqueue(std::function<void()> hand_off) override { hand_off(); }
  void shutdown() override {}
};

// httplib's server with its connections behind a RequestGate: serve() answers one request on a
// socket whose request has arrived (httplib's own parsing, routing and responses).
class GatedServer : public httplib::Server {
 public:
  GatedServer(std::chrono::milliseconds read, std::chrono::milliseconds write)
      : read_ms_(static_cast<int>(read.count())), write_ms_(static_cast<int>(write.count())) {
    new_task_queue = [] { return new HandOver; };
  }
  void set_gate(RequestGate* gate) { gate_ = gate; }
  // httplib listens with a backlog of 5: a crowd connecting at once would see SYNs dropped (a
  // fresh client's connect then waits 1 s for its retry). Listening again widens it.
  void widen_backlog() { ::listen(svr_sock_, 512); }
  // Serves `fd` (bound and listening) as if bind_to_port had made it.
  void adopt(int fd) { svr_sock_ = fd; }
  void serve(int fd) {
    FdStream stream(fd, read_ms_, write_ms_);
    bool closed = false;
    process_request(stream, true, closed, nullptr);
  }

 private:
  bool process_and_close_socket(::socket_t sock) override {
    gate_->admit(sock);
    return true;
  }
  int read_ms_, write_ms_;
  RequestGate* gate_ = nullptr;
};

// The port bound (`address`'s, or any free one for port 0), trying every 50 ms for `patience`;
// -1 when it could not be.
int bind_within(httplib::Server& server, const ListenAddress& address,
                std::chrono::milliseconds patience) {
  const auto give_up = std::chrono::steady_clock::now() + patience;
  for (;;) {
    const int port = address.port == 0 ? server.bind_to_any_port(address.host)
                     : server.bind_to_port(address.host, address.port) ? address.port
                                                                       : -1;
    if (port > 0 || std::chrono::steady_clock::now() >= give_up) return port;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

}  // namespace

int bound_port(int fd) {
  sockaddr_in a{};
  socklen_t length = sizeof a;
  if (getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length) != 0 || a.sin_family != AF_INET)
    return -1;
  return ntohs(a.sin_port);
}

int open_listener(const ListenAddress& address) {
  const std::string where = address.host + ":" + std::to_string(address.port);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(address.port));
  const std::string host = address.host == "localhost" ? "127.0.0.1" : address.host;
  if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1)
    throw std::runtime_error("the view cannot listen on " + where + ": not an IPv4 address");
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);  // no SOCK_CLOEXEC: it is handed down
  int yes = 1;
  if (fd < 0 || setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes) != 0 ||
      ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd, 512) != 0) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    throw std::runtime_error("the view cannot listen on " + where + ": " + why);
  }
  return fd;
}

bool ListenAddress::loopback() const { return host == "localhost" || host.rfind("127.", 0) == 0; }

ListenAddress parse_listen_address(const std::string& text, const std::string& flag) {
  const auto fail = [&](const std::string& why) {
    return std::invalid_argument(flag + " " + text + ": " + why +
                                 " (expected HOST:PORT, HOST an IPv4 address or localhost, "
                                 "PORT 0-65535, e.g. 127.0.0.1:8080)");
  };
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) throw fail("no HOST:PORT");
  ListenAddress a;
  a.host = text.substr(0, colon);
  const std::string port = text.substr(colon + 1);
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos)
    throw fail("port '" + port + "' is not a number");
  a.port = std::stoi(port);
  if (a.port > 65535) throw fail("port " + port + " is above 65535");
  in_addr parsed{};
  if (a.host != "localhost" && inet_pton(AF_INET, a.host.c_str(), &parsed) != 1)
    throw fail("host '" + a.host + "' is not an IPv4 address");
  return a;
}

ViewServer::ViewServer(const Feed& feed, ServerOptions options)
    : feed_(feed), options_(std::move(options)) {
  if (options_.allow_stop && options_.token.empty()) options_.token = make_token();
  if (options_.allow_stop && options_.token.size() < 16)
    throw std::invalid_argument("the view's stop token must have at least 16 characters");
  const std::filesystem::path web = options_.web_dir.empty() ? RTHS_VIEW_WEB_DIR : options_.web_dir;
  const std::filesystem::path uplot =
      options_.uplot_dir.empty() ? RTHS_VIEW_UPLOT_DIR : options_.uplot_dir;
  files_["/"] = {"text/html; charset=utf-8", read_whole(web / "index.html")};
  files_["/view.js"] = {"text/javascript; charset=utf-8", read_whole(web / "view.js")};
  files_["/view.css"] = {"text/css; charset=utf-8", read_whole(web / "view.css")};
  files_["/sites.js"] = {"text/javascript; charset=utf-8", read_whole(web / "sites.js")};
  files_["/uPlot.iife.min.js"] = {"text/javascript; charset=utf-8",
                                  read_whole(uplot / "uPlot.iife.min.js")};
  files_["/uPlot.min.css"] = {"text/css; charset=utf-8", read_whole(uplot / "uPlot.min.css")};
  const auto snapshot_of = [this](const Feed* feed) {
    return std::make_unique<SnapshotCache>(
        [this, feed] {
          FeedCursor cursor;
          nlohmann::json j = feed->since(cursor);
          j["mode"] = options_.mode;
          return j.dump();
        },
        options_.snapshot_period);
  };
  snapshots_ = snapshot_of(&feed_);
  if (options_.second) {
    second_snapshots_ = snapshot_of(options_.second);
    files_["/compare"] = {"text/html; charset=utf-8", read_whole(web / "compare.html")};
  }
  auto gated = std::make_unique<GatedServer>(std::chrono::seconds(2), options_.write_timeout);
  GateOptions gate = options_.gate;
  gate.workers = options_.max_streams + 4;
  gate_ = std::make_unique<RequestGate>(gate, [g = gated.get()](int fd) { g->serve(fd); });
  gated->set_gate(gate_.get());
  GatedServer& listener = *gated;
  server_ = std::move(gated);
  server_->set_payload_max_length(4096);
  routes();
  server_->set_socket_options([](::socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  if (options_.listen_fd >= 0) {
    port_ = bound_port(options_.listen_fd);
    listener.adopt(options_.listen_fd);
  } else {
    port_ = bind_within(*server_, options_.address, options_.bind_for);
  }
  const auto& a = options_.address;
  if (port_ <= 0)
    throw std::runtime_error("the view cannot listen on " + a.host + ":" + std::to_string(a.port) +
                             " (in use, or not an address of this host)");
  listener.widen_backlog();
  thread_ = std::thread([this] {
    enter_view_thread("view-accept", options_.gate.nice);
    server_->listen_after_bind();
    listen_returned_.store(true);
  });
}

std::string ViewServer::foreign(const std::string& host_header, const std::string& origin,
                                const std::string& local_address) {
  const std::string host = lower(host_header);
  const std::vector<std::string> names{"127.0.0.1", "localhost", "[::1]",
                                       lower(options_.address.host), local_address};
  if (!names_served(host, names, port_)) {
    ++bad_host_;
    return "Host '" + host_header + "' is not this view's address: open it as " + url();
  }
  if (!origin.empty() && lower(origin) != "http://" + host) {
    ++cross_origin_;
    return "a request from " + origin + " (another origin) is refused";
  }
  return "";
}

void ViewServer::routes() {
  httplib::Server& s = *server_;
  s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    const std::string why =
        foreign(req.get_header_value("Host"), req.get_header_value("Origin"), req.local_addr);
    if (why.empty()) return httplib::Server::HandlerResponse::Unhandled;
    res.status = 403;
    res.set_content(why, "text/plain");
    return httplib::Server::HandlerResponse::Handled;
  });
  for (const auto& [path, file] : files_)
    s.Get(path, [this, &file = file](const httplib::Request&, httplib::Response& res) {
      res.set_content(file.second, file.first.c_str());
      res.set_header("Cache-Control", "no-store");
    });
  s.Get("/api/health", [this](const httplib::Request&, httplib::Response& res) {
    nlohmann::json j = {{"mode", options_.mode},
                        {"stop_enabled", options_.allow_stop || options_.desk},
                        {"token_required", options_.allow_stop || options_.desk},
                        {"roles", options_.desk != nullptr},
                        {"counters", counters()}};
    if (options_.desk)
      for (const auto& [lab, nodes] : options_.desk->labs()) j["labs"][lab] = nodes;
    res.set_content(j.dump(), "application/json");
  });
  s.Post("/api/stop", [this](const httplib::Request& req, httplib::Response& res) {
    if (options_.desk) return control(req, res, "stop");
    if (!options_.allow_stop || !options_.on_stop) {
      res.status = 403;
      res.set_content("the stop button is off: start the view with --view-stop", "text/plain");
      return;
    }
    if (!same_token(req.get_header_value("X-RTHS-Token"), options_.token)) {
      ++bad_token_;
      res.status = 403;
      res.set_content(
          "wrong or missing token (X-RTHS-Token): open the address printed when the view started, "
          "the one with ?token=",
          "text/plain");
      return;
    }
    ++stop_requests_;
    if (!stop_requested_.exchange(true)) options_.on_stop();
    res.status = 202;
    res.set_content("stop requested: HOLD, then STOP (\"stopped from the view\")", "text/plain");
  });
  data_routes(s);
  control_routes(s);
  s.set_error_handler(
      httplib::Server::HandlerWithResponse([this](const httplib::Request&, httplib::Response& res) {
        if (res.status == 404)
          ++not_found_;
        else if (res.status >= 400)
          ++refused_;
        if (res.body.empty()) res.set_content(std::to_string(res.status) + "\n", "text/plain");
        return httplib::Server::HandlerResponse::Handled;
      }));
}

const Feed* ViewServer::feed_named(const httplib::Request& req, httplib::Response& res) const {
  const std::string run = req.has_param("run") ? req.get_param_value("run") : "a";
  if (run == "a") return &feed_;
  if (run == "b" && options_.second) return options_.second;
  res.status = 404;
  res.set_content("no run '" + run + "' in this view" + (options_.second ? " (a or b)" : " (a)"),
                  "text/plain");
  return nullptr;
}

// The run's data: its snapshot, its stream and, comparing two runs, both runs' summaries.
// One server-sent-events stream per client: the feed's news at most once per update_period.
// The provider runs on the connection's pool thread; a write that cannot go out within
// write_timeout (a client that does not read) fails and drops the connection.
void ViewServer::data_routes(httplib::Server& s) {
  s.Get("/api/snapshot", [this](const httplib::Request& req, httplib::Response& res) {
    if (!admitted(req, res)) return;
    const Feed* feed = feed_named(req, res);
    if (!feed) return;
    const auto copy = (feed == &feed_ ? snapshots_ : second_snapshots_)->get();
    if (!copy) {  // the first build failed for every waiting client
      res.status = 503;
      return;
    }
    res.set_content(*copy, "application/json");
  });
  if (options_.second)
    s.Get("/api/compare", [this](const httplib::Request& req, httplib::Response& res) {
      if (!admitted(req, res)) return;
      res.set_content(options_.comparison.dump(), "application/json");
    });
  s.Get("/api/stream", [this](const httplib::Request& req, httplib::Response& res) {
    if (!admitted(req, res)) return;
    const Feed* feed = feed_named(req, res);
    if (!feed) return;
    if (streams_.fetch_add(1) >= options_.max_streams) {
      streams_.fetch_sub(1);
      ++streams_refused_;
      res.status = 503;
      res.set_content("too many open views", "text/plain");
      return;
    }
    ++streams_served_;
    res.set_header("Cache-Control", "no-store");
    auto cursor = std::make_shared<FeedCursor>();
    auto last = std::make_shared<std::chrono::steady_clock::time_point>();
    auto seen = std::make_shared<std::uint64_t>(0);
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, feed, cursor, last, seen](std::size_t, httplib::DataSink& sink) {
          if (stopping_.load()) return false;
          std::this_thread::sleep_until(*last + options_.update_period);
          feed->wait_change(*seen, options_.update_period);
          const bool finished = feed->finished();
          nlohmann::json j = feed->since(*cursor);
          *seen = j["version"].get<std::uint64_t>();
          j["mode"] = options_.mode;
          j["server_realtime_ns"] = transport::realtime_ns();
          const std::string message = "data: " + j.dump() + "\n\n";
          *last = std::chrono::steady_clock::now();
          if (!sink.write(message.data(), message.size())) {
            ++streams_dropped_;
            return false;
          }
          ++updates_sent_;
          if (finished) sink.done();
          return true;
        },
        [this](bool) { streams_.fetch_sub(1); });
  });
}

// The control room's presses (a desk only): the token's role judged by the desk, which queues
// the press for the loop; the answer names what happens or why it is refused.
void ViewServer::control(const httplib::Request& req, httplib::Response& res,
                         const std::string& action) {
  const auto press = options_.desk->press(req.get_header_value("X-RTHS-Token"), action,
                                          req.get_header_value("X-RTHS-Lab"),
                                          static_cast<std::int64_t>(feed_.steps_seen()) - 1);
  if (!press) {
    ++bad_token_;
    res.status = 403;
    res.set_content("wrong or missing token (X-RTHS-Token): use the address printed for your role",
                    "text/plain");
    return;
  }
  if (press->stop) {
    ++stop_requests_;
    stop_requested_.store(true);
  }
  res.status = press->allowed ? 202 : 403;
  res.set_content(press->text(), "text/plain");
}

bool ViewServer::admitted(const httplib::Request& req, httplib::Response& res) {
  if (!options_.desk) return true;
  const std::string token = req.get_header_value("X-RTHS-Token");
  if (options_.desk->crew().identify(token)) return true;
  ++bad_token_;
  res.status = token.empty() ? 401 : 403;
  res.set_content(token.empty() ? "this run's view is for its crew: send your role's token "
                                  "(X-RTHS-Token), as the address printed for your role does"
                                : "no role has this token: use the address printed for your role",
                  "text/plain");
  return false;
}

void ViewServer::control_routes(httplib::Server& s) {
  s.Post("/api/hold", [this](const httplib::Request& req, httplib::Response& res) {
    if (!options_.desk) {
      res.status = 403;
      res.set_content("this view has no control room (roles): HOLD is the director's stop",
                      "text/plain");
      return;
    }
    control(req, res, "hold");
  });
  s.Post("/api/whoami", [this](const httplib::Request& req, httplib::Response& res) {
    const auto role = options_.desk
                          ? options_.desk->crew().identify(req.get_header_value("X-RTHS-Token"))
                          : std::nullopt;
    if (!role) {
      ++bad_token_;
      res.status = 403;
      res.set_content("no role has this token", "text/plain");
      return;
    }
    static const char* const kinds[] = {"director", "operator", "viewer"};
    res.set_content(nlohmann::json{{"role", kinds[static_cast<int>(role->kind)]},
                                   {"lab", role->lab},
                                   {"name", role->name()}}
                        .dump(),
                    "application/json");
  });
}

ViewServer::~ViewServer() { shutdown(std::chrono::milliseconds(0)); }

std::string ViewServer::url() const {
  return "http://" + options_.address.host + ":" + std::to_string(port_) + "/";
}

std::string ViewServer::page_url() const {
  return options_.allow_stop ? url() + "?token=" + options_.token : url();
}

nlohmann::json ViewServer::counters() const {
  return {{"refused", refused_.load()},
          {"not_found", not_found_.load()},
          {"bad_token", bad_token_.load()},
          {"bad_host", bad_host_.load()},
          {"cross_origin", cross_origin_.load()},
          {"streams_open", streams_.load()},
          {"streams_served", streams_served_.load()},
          {"streams_refused", streams_refused_.load()},
          {"streams_dropped", streams_dropped_.load()},
          {"updates_sent", updates_sent_.load()},
          {"stop_requests", stop_requests_.load()},
          {"snapshot_builds", snapshots_->builds()},
          {"snapshots_served", snapshots_->served()},
          {"connections", gate_->counters()}};
}

// httplib's stop() does nothing before its accept loop has begun (is_running): a view shut down
// before its listening thread first ran would then join a thread that listens for ever. Stop is
// called once: a second call on a stopping server asserts in httplib.
void ViewServer::stop_listening() {
  while (!server_->is_running() && !listen_returned_.load())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  server_->stop();
}

void ViewServer::shutdown(std::chrono::milliseconds linger) {
  const auto until = std::chrono::steady_clock::now() + linger;
  while (streams_.load() > 0 && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  stopping_.store(true);
  if (server_) stop_listening();
  if (thread_.joinable()) thread_.join();
  if (gate_) gate_->stop();
}

}  // namespace rths::view
