// A finished record served as the page: the whole run in replay mode with its verdict (and, for a
// real-time record that overran, the deadline diagnosis `rths launch` prints), a sites run's
// folder with its sites, two runs compared side by side, and the address
// handed over from a view that has just stopped, never shared with one still listening.
#include "view/record_view.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <thread>

#include "tests/runtime/test_support.h"
#include "tests/support/in_process_run.h"
#include "tests/view/recorded_run.h"

namespace rths::view {
namespace {

using namespace std::chrono_literals;

std::filesystem::path record_path(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("rths_record_view_" + name + "_" + std::to_string(::getpid()) + ".rthsrec");
}

// The paper frame's lag_shift_14ms run in lockstep, recorded; its contents.
runtime::RecordContents recorded_run(const std::string& name) {
  return test::recorded_paper_frame(test::prepare(test::paper_frame_study(1.0, "")),
                                    "record-view-" + name, record_path(name));
}

// `entries` framed as the writer frames them, into the file `path`.
void write_record(const std::vector<runtime::RecordEntry>& entries,
                  const std::filesystem::path& path) {
  std::string bytes;
  for (const auto& entry : entries) runtime::append_record_frame(entry, bytes);
  std::ofstream(path, std::ios::binary) << bytes;
}

nlohmann::json snapshot(const std::string& url) {
  httplib::Client client(url.substr(0, url.size() - 1));  // http://HOST:PORT
  client.set_read_timeout(10s);
  const auto answer = client.Get("/api/snapshot");
  EXPECT_TRUE(answer);
  return answer ? nlohmann::json::parse(answer->body) : nlohmann::json::object();
}

TEST(RecordView, ServesTheWholeFinishedRunWithItsVerdict) {
  const runtime::RecordContents contents = recorded_run("lockstep");
  const auto path = record_path("lockstep_served");
  write_record(contents.entries, path);
  RecordView view(path, {"127.0.0.1", 0});
  const auto j = snapshot(view.url());
  std::filesystem::remove(path);
  EXPECT_EQ(j["mode"], "replay");
  EXPECT_TRUE(j["status"]["finished"]);
  EXPECT_EQ(j["status"]["steps"], contents.steps().size());
  EXPECT_EQ(view.steps(), contents.steps().size());
  EXPECT_EQ(j["status"]["verdict"]["badge"], "completed");
  EXPECT_EQ(j["status"]["verdict"]["level"], "ok");
  EXPECT_EQ(j["status"]["verdict"]["diagnosis"], "");
  EXPECT_FALSE(view.truncated());
}

// The same run as a real-time record whose rows overran 7 times (2 in a row at most) under a
// tolerance of 5 %: within the verdict, so a warning naming them, with the diagnosis beneath.
TEST(RecordView, ARealTimeRecordThatOverranShowsTheWarningAndTheDiagnosis) {
  runtime::RecordContents contents = recorded_run("overran");
  auto& header = *contents.entries.front().mutable_header();
  header.set_clock("real_time");
  header.mutable_study()->mutable_deployment()->set_clock(config::Deployment::REAL_TIME);
  header.mutable_study()->mutable_deployment()->set_max_overrun_fraction(0.05);
  int overran = 0;
  for (auto& entry : contents.entries) {
    if (!entry.has_step()) continue;
    const std::int64_t k = entry.step().step();
    entry.mutable_step()->set_step_wall(0.2e-3);
    if (k == 100 || k == 101 || (k >= 300 && k < 800 && k % 100 == 0)) {
      entry.mutable_step()->set_overrun(true);
      entry.mutable_step()->set_lateness(0.5e-3);
      ++overran;
    }
  }
  ASSERT_EQ(overran, 7);
  const auto path = record_path("overran_served");
  write_record(contents.entries, path);
  RecordView view(path, {"127.0.0.1", 0});
  const auto verdict = snapshot(view.url())["status"]["verdict"];
  std::filesystem::remove(path);
  EXPECT_EQ(verdict["level"], "warning");
  EXPECT_EQ(verdict["badge"], "completed with 7 overruns");
  const std::string diagnosis = verdict["diagnosis"];
  EXPECT_EQ(diagnosis.rfind("deadline misses: 7 of ", 0), 0u) << diagnosis;
  EXPECT_NE(diagnosis.find("the record: usable as recorded"), std::string::npos) << diagnosis;
}

// A header whose recorded DOFs are not ascending DOFs of the model is refused before anything is
// sized or predicted from it, the error naming the field and its value.
TEST(RecordView, ARecordWhoseHeaderTheViewCannotSizeFromIsRefusedNamingTheField) {
  runtime::RecordContents contents = recorded_run("crafted");
  auto& header = *contents.entries.front().mutable_header();
  ASSERT_EQ(header.dofs(), 1);
  header.clear_recorded_dofs();
  header.add_recorded_dofs(0);
  header.add_recorded_dofs(0);
  const auto path = record_path("crafted_served");
  write_record(contents.entries, path);
  try {
    RecordView view(path, {"127.0.0.1", 0});
    ADD_FAILURE() << "a header with recorded_dofs 0, 0 was served";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("run header: recorded_dofs[1] 0 is not a DOF of 0..0"),
              std::string::npos)
        << e.what();
  }
  std::filesystem::remove(path);
}

TEST(RecordView, ARecordThatCannotBeReadOrHasNoHeaderIsRefused) {
  EXPECT_THROW(RecordView(record_path("missing"), {"127.0.0.1", 0}), std::invalid_argument);
  const auto path = record_path("no_header");
  runtime::RecordEntry step;
  step.mutable_step()->set_step(0);
  write_record({step}, path);
  EXPECT_THROW(RecordView(path, {"127.0.0.1", 0}), std::invalid_argument);
  std::filesystem::remove(path);
}

nlohmann::json get_json(const std::string& url, const std::string& path, int* status = nullptr) {
  httplib::Client client(url.substr(0, url.size() - 1));
  client.set_read_timeout(10s);
  const auto answer = client.Get(path);
  if (status) *status = answer ? answer->status : -1;
  return answer && answer->status == 200 ? nlohmann::json::parse(answer->body)
                                         : nlohmann::json::object();
}

// A fresh folder for a run's output.
std::filesystem::path run_folder(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rths_record_view_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A sites run's folder (its record and the sites.json `rths sites` writes beside it) is served
// with its sites as the live page had them, and every actuator of every site on the record's
// one time axis (each actuator's column one value per time).
TEST(RecordView, ASitesRunsFolderShowsEverySitesActuatorsOnOneTimeAxis) {
  const runtime::RecordContents contents = recorded_run("sites");
  const auto dir = run_folder("sites");
  write_record(contents.entries, dir / "lab_test.rthsrec");
  const auto& links = contents.header()->link_node_ids();
  ASSERT_GE(links.size(), 2);
  const nlohmann::json sites = {
      {{"name", "site_a"}, {"nodes", {0, links[0]}}, {"lab_nodes", nlohmann::json::array()}},
      {{"name", "lab_b"},
       {"nodes", std::vector<int>(links.begin() + 1, links.end())},
       {"lab_nodes", std::vector<int>(links.begin() + 1, links.end())}}};
  std::ofstream(dir / "sites.json") << sites.dump();
  RecordView view(dir, {"127.0.0.1", 0});
  const auto j = snapshot(view.url());
  EXPECT_EQ(j["context"]["sites"], sites);
  const int actuators = j["header"]["actuators"];
  EXPECT_EQ(actuators, contents.header()->actuators());
  ASSERT_GT(actuators, 0);
  const auto& samples = j["samples"];
  const std::size_t times = samples["time_s"].size();
  EXPECT_GT(times, 10u);
  ASSERT_EQ(samples["command_mm"].size(), static_cast<std::size_t>(actuators));
  for (int a = 0; a < actuators; ++a) {
    EXPECT_EQ(samples["command_mm"][a].size(), times) << a;
    EXPECT_EQ(samples["measured_mm"][a].size(), times) << a;
  }
  EXPECT_EQ(samples["round_trip_ms"].size(), static_cast<std::size_t>(links.size()));
  std::filesystem::remove_all(dir);
}

TEST(RecordView, AFolderWithNoneOrSeveralRecordsOrABadSitesFileIsRefusedNamingIt) {
  const auto dir = run_folder("refused");
  const auto refusal = [&] {
    try {
      RecordView view(dir, {"127.0.0.1", 0});
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("served");
  };
  EXPECT_NE(refusal().find("holds no run record (.rthsrec)"), std::string::npos) << refusal();
  const runtime::RecordContents contents = recorded_run("refused");
  write_record(contents.entries, dir / "a.rthsrec");
  std::ofstream(dir / "sites.json") << R"({"name": "site_a"})";
  EXPECT_NE(refusal().find("sites.json is not a list of {name, nodes, lab_nodes}"),
            std::string::npos)
      << refusal();
  std::filesystem::remove(dir / "sites.json");
  write_record(contents.entries, dir / "b.rthsrec");
  EXPECT_NE(refusal().find("holds 2 run records (a.rthsrec, b.rthsrec): name the one to view"),
            std::string::npos)
      << refusal();
  std::filesystem::remove_all(dir);
}

// Two runs compared: /api/compare holds both (run ids, records, E_peak and E_rms per DOF), each
// run's data is served by name (?run=a, ?run=b; any other 404), /compare shows both pages.
TEST(RecordView, TwoRunsAreServedSideBySideWithEachOnesErrorMeasures) {
  runtime::RecordContents contents = recorded_run("compare");
  const auto a = record_path("compare_a"), b = record_path("compare_b");
  write_record(contents.entries, a);
  contents.entries.front().mutable_header()->set_run_id("run-b");
  for (auto& entry : contents.entries)  // run B's response 10 % larger than run A's
    if (entry.has_step())
      for (double& u : *entry.mutable_step()->mutable_displacement()) u *= 1.1;
  write_record(contents.entries, b);
  RecordView view(a, b, {"127.0.0.1", 0});
  const auto runs = get_json(view.url(), "/api/compare")["runs"];
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0]["run_id"], "record-view-compare");
  EXPECT_EQ(runs[1]["run_id"], "run-b");
  EXPECT_EQ(runs[0]["record"], a.string());
  EXPECT_EQ(runs[1]["record"], b.string());
  const int dofs = contents.header()->dofs();
  for (const auto& run : runs) {
    ASSERT_EQ(run["e_peak_pct"].size(), static_cast<std::size_t>(dofs)) << run;
    ASSERT_EQ(run["e_rms_pct"].size(), static_cast<std::size_t>(dofs)) << run;
  }
  // In lockstep run A equals its prediction; B is 10 % off it everywhere.
  for (int d = 0; d < dofs; ++d) {
    EXPECT_LT(runs[0]["e_rms_pct"][d].get<double>(), 1e-6) << d;
    EXPECT_NEAR(runs[1]["e_rms_pct"][d].get<double>(), 10.0, 0.01) << d;
    EXPECT_NEAR(runs[1]["e_peak_pct"][d].get<double>(), 10.0, 0.01) << d;
  }
  EXPECT_EQ(get_json(view.url(), "/api/snapshot?run=b")["header"]["run_id"], "run-b");
  EXPECT_EQ(get_json(view.url(), "/api/snapshot?run=a")["header"]["run_id"], "record-view-compare");
  int status = 0;
  get_json(view.url(), "/api/snapshot?run=c", &status);
  EXPECT_EQ(status, 404);
  httplib::Client client(view.url().substr(0, view.url().size() - 1));
  const auto page = client.Get("/compare");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("src=\"/?run=b\""), std::string::npos);
  std::filesystem::remove(a);
  std::filesystem::remove(b);
}

// Whether a socket with SO_REUSEPORT can bind 127.0.0.1:`port` (closed again at once).
bool binds_beside(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  int yes = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEPORT, &yes, sizeof yes);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool bound = bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  close(fd);
  return bound;
}

// A live view on a port: a second server is refused it (never shared: SO_REUSEPORT is off);
// once the first stops, after a page was served (its connection in TIME_WAIT on that port), the
// record's view takes the port within its bind_for.
TEST(RecordView, TakesOverThePortOfAViewThatHasJustStoppedButNeverSharesALiveOne) {
  const runtime::RecordContents contents = recorded_run("handover");
  const auto path = record_path("handover_served");
  write_record(contents.entries, path);
  Feed live_feed;
  auto live = std::make_unique<ViewServer>(live_feed, ServerOptions{});
  const ListenAddress address{"127.0.0.1", live->port()};
  ASSERT_EQ(httplib::Client(live->url().substr(0, live->url().size() - 1)).Get("/")->status, 200);
  // A socket asking for SO_REUSEPORT binds a port only when its listener asked for it too.
  ASSERT_FALSE(binds_beside(address.port)) << "the live view listens with SO_REUSEPORT";
  EXPECT_THROW(RecordView(path, address), std::runtime_error);
  std::thread stop_live([&] {
    std::this_thread::sleep_for(300ms);
    live.reset();
  });
  const auto start = std::chrono::steady_clock::now();
  RecordView view(path, address, 5s);
  const auto waited = std::chrono::steady_clock::now() - start;
  stop_live.join();
  EXPECT_GE(waited, 250ms);
  EXPECT_LT(waited, 5s);
  EXPECT_EQ(snapshot(view.url())["mode"], "replay");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace rths::view
