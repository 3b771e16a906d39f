// The view's guard over real HTTP on loopback: the stop needs the run's token (loopback
// included), a request from another origin or naming another host is refused (403) and the run
// goes on, and the page is still served at the address the program prints.
#include "view/server.h"

#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace rths::view {
namespace {

// A view with the stop button on, counting the stops it asked for.
struct StopView {
  explicit StopView(ServerOptions options = {}) : server(feed, with_stop(std::move(options))) {}
  ServerOptions with_stop(ServerOptions options) {
    options.allow_stop = true;
    options.on_stop = [this] { ++stops; };
    return options;
  }
  std::string here() const { return "127.0.0.1:" + std::to_string(server.port()); }
  Feed feed;
  std::atomic<int> stops{0};
  ViewServer server;
};

// The answer's status to `method` of `path` on the view at 127.0.0.1:`port` with `headers` (a
// Host among them replaces the client's own); -1 when there was no answer.
int status_of(int port, const std::string& method, const std::string& path,
              const httplib::Headers& headers) {
  httplib::Client client("127.0.0.1", port);
  // Bounded: a view that stops answering fails the test instead of holding it to ctest's limit.
  client.set_connection_timeout(10);
  client.set_read_timeout(20);
  client.set_write_timeout(10);
  const auto answer =
      method == "POST" ? client.Post(path.c_str(), headers, "", "") : client.Get(path, headers);
  return answer ? answer->status : -1;
}

TEST(ViewStopGuard, TheStopNeedsItsTokenOnLoopbackTooAndEachViewMakesItsOwn) {
  StopView view, other;
  const std::string& token = view.server.token();
  ASSERT_EQ(token.size(), 32u);
  EXPECT_EQ(token.find_first_not_of("0123456789abcdef"), std::string::npos) << token;
  EXPECT_NE(token, other.server.token());
  EXPECT_EQ(view.server.page_url(), view.server.url() + "?token=" + token);
  const int port = view.server.port();
  EXPECT_EQ(status_of(port, "POST", "/api/stop", {}), 403);
  EXPECT_EQ(status_of(port, "POST", "/api/stop", {{"X-RTHS-Token", other.server.token()}}), 403);
  EXPECT_EQ(status_of(port, "POST", "/api/stop", {{"X-RTHS-Token", token.substr(0, 31)}}), 403);
  EXPECT_EQ(view.server.counters()["bad_token"], 3);
  EXPECT_EQ(view.stops, 0);
  EXPECT_FALSE(view.server.stop_requested());
  EXPECT_EQ(status_of(port, "POST", "/api/stop", {{"X-RTHS-Token", token}}), 202);
  EXPECT_EQ(view.stops, 1);
}

// httplib's stop() does nothing until its accept loop has begun: a view destroyed before its
// listening thread first ran would join a thread that listens for ever.
TEST(ViewStopGuard, AViewDestroyedAtOnceAfterItsBirthStillStops) {
  auto born_and_destroyed = std::make_shared<std::promise<void>>();
  std::future<void> done = born_and_destroyed->get_future();
  std::thread([born_and_destroyed] {
    for (int i = 0; i < 300; ++i) StopView view;
    born_and_destroyed->set_value();
  }).detach();
  // Bounded: a hang fails here with its cause instead of at ctest's limit.
  ASSERT_EQ(done.wait_for(std::chrono::seconds(120)), std::future_status::ready)
      << "a view destroyed right after its construction never stopped listening";
}

TEST(ViewStopGuard, ACrossOriginPostIsRefusedEvenWithTheTokenAndTheRunGoesOn) {
  StopView view;
  const int port = view.server.port();
  const std::string& token = view.server.token();
  for (const std::string& origin : std::vector<std::string>{
           "http://evil.example", "null", "http://127.0.0.1:" + std::to_string(port + 1),
           "https://" + view.here(), "http://localhost:" + std::to_string(port)})
    EXPECT_EQ(status_of(port, "POST", "/api/stop", {{"Origin", origin}, {"X-RTHS-Token", token}}),
              403)
        << origin;
  EXPECT_EQ(view.server.counters()["cross_origin"], 5);
  EXPECT_EQ(view.stops, 0);
  EXPECT_FALSE(view.server.stop_requested());
  // The page's own request: same origin, with the token.
  EXPECT_EQ(status_of(port, "POST", "/api/stop",
                      {{"Origin", "http://" + view.here()}, {"X-RTHS-Token", token}}),
            202);
  EXPECT_EQ(view.stops, 1);
}

TEST(ViewStopGuard, AHostThatIsNotTheAddressServedIsRefusedAgainstDnsRebinding) {
  StopView view;
  const int port = view.server.port();
  const std::string& token = view.server.token();
  const std::string rebound = "evil.example:" + std::to_string(port);
  EXPECT_EQ(
      status_of(port, "POST", "/api/stop",
                {{"Host", rebound}, {"Origin", "http://" + rebound}, {"X-RTHS-Token", token}}),
      403);
  EXPECT_EQ(status_of(port, "GET", "/", {{"Host", rebound}}), 403);
  EXPECT_EQ(status_of(port, "GET", "/api/snapshot", {{"Host", rebound}}), 403);
  EXPECT_EQ(status_of(port, "GET", "/", {{"Host", "127.0.0.1:" + std::to_string(port + 1)}}), 403);
  EXPECT_EQ(status_of(port, "GET", "/", {{"Host", "127.0.0.1"}}), 403);
  EXPECT_EQ(view.server.counters()["bad_host"], 5);
  EXPECT_EQ(view.stops, 0);
  for (const std::string name : {"127.0.0.1", "localhost", "LocalHost", "[::1]"})
    EXPECT_EQ(status_of(port, "GET", "/", {{"Host", name + ":" + std::to_string(port)}}), 200)
        << name;
}

TEST(ViewStopGuard, ThePageAndItsScriptAreServedAtTheAddressPrinted) {
  StopView view;
  httplib::Client browser("127.0.0.1", view.server.port());
  const auto page = browser.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/view.js"), std::string::npos);
  const auto script = browser.Get("/view.js");
  ASSERT_TRUE(script);
  EXPECT_NE(script->body.find("X-RTHS-Token"), std::string::npos);
  const auto health = browser.Get("/api/health", {{"Origin", "http://" + view.here()}});
  ASSERT_TRUE(health);
  EXPECT_EQ(nlohmann::json::parse(health->body)["token_required"], true);
  EXPECT_EQ(view.stops, 0);
}

TEST(ViewStopGuard, BoundToEveryAddressItAnswersToTheAddressEachConnectionReached) {
  ServerOptions options;
  options.address = {"0.0.0.0", 0};
  StopView view(options);
  const int port = view.server.port();
  httplib::Client second("127.0.0.2", port);  // Host: 127.0.0.2:PORT, the address reached
  const auto page = second.Get("/");
  ASSERT_TRUE(page) << "127.0.0.2 is not reachable here";
  EXPECT_EQ(page->status, 200);
  const auto other = second.Get("/", {{"Host", "127.0.0.3:" + std::to_string(port)}});
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 403);
  EXPECT_EQ(status_of(port, "GET", "/", {{"Host", "0.0.0.0:" + std::to_string(port)}}), 200);
}

}  // namespace
}  // namespace rths::view
