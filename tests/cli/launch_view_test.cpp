// `rths launch --view` once the run is over: the page stays on the finished run, at the same
// address, for --view-for seconds, and launch then exits with the run's own status (a failed
// run never 0). Real processes over Cyclone DDS on loopback (the shared domain, each test on
// topics of its own), probed over HTTP every 100 ms from the start of launch to its exit.
// The run-record headers (and Eigen through them) come before httplib.h, whose <resolv.h> defines
// _res, a parameter name in Eigen.
#include "runtime/record/record.h"
#include "tests/support/real_time_run.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iterator>
#include <optional>
#include <thread>

#include "tests/cli/cli_support.h"
#include "tests/support/dds_scope.h"
#include "util/process.h"

namespace rths::cli_test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// A port free on loopback now (the kernel's pick; launch binds it a moment later).
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  socklen_t length = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &length);
  close(fd);
  return ntohs(addr.sin_port);
}

// One answer of the view (or none): when, and the mode and verdict it served.
struct Probe {
  double at_s = 0;  // since launch started
  bool answered = false;
  std::string mode;   // "live" or "replay"
  std::string badge;  // the finished run's, from its snapshot
  std::string level;
};

// GET / and, when it answers, the snapshot: what the view at `port` serves now.
Probe probe(int port, double at_s) {
  Probe p;
  p.at_s = at_s;
  httplib::Client client("127.0.0.1", port);
  client.set_connection_timeout(1s);
  client.set_read_timeout(2s);
  const auto page = client.Get("/");
  if (!page || page->status != 200) return p;
  const auto snapshot = client.Get("/api/snapshot");
  if (!snapshot || snapshot->status != 200) return p;
  const auto j = nlohmann::json::parse(snapshot->body);
  p.answered = true;
  p.mode = j.value("mode", "");
  const auto verdict = j["status"].value("verdict", nlohmann::json::object());
  p.badge = verdict.value("badge", "");
  p.level = verdict.value("level", "");
  return p;
}

// `rths launch` with these arguments, its view probed every 100 ms until it exits (at most
// 300 s); its exit code and the probes.
std::pair<int, std::vector<Probe>> launch_and_probe(const std::string& config, int port,
                                                    const std::vector<std::string>& extra,
                                                    const std::filesystem::path& dir) {
  std::vector<std::string> args{"launch",
                                config,
                                "--out",
                                (dir / "out").string(),
                                "--no-plots",
                                "--bin-dir",
                                RTHS_BINARY_DIR,
                                "--view",
                                "127.0.0.1:" + std::to_string(port)};
  args.insert(args.end(), extra.begin(), extra.end());
  util::ChildProcess launch(kRths, args, dir / "launch.log");
  const auto start = Clock::now();
  std::vector<Probe> probes;
  while (launch.running() && Clock::now() - start < 300s) {
    probes.push_back(probe(port, std::chrono::duration<double>(Clock::now() - start).count()));
    std::this_thread::sleep_for(100ms);
  }
  const auto exit = launch.wait_for(10s);
  return {exit.value_or(-1), probes};
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string study(const std::filesystem::path& dir, const std::string& clock, int domain,
                  const std::string& cases) {
  const auto path = dir / "study.textproto";
  const std::string deployment =
      clock == "REAL_TIME"
          // Fail-safe windows wide, the overrun tolerance off: this shared machine's stalls must
          // not decide the run; what happens after it is the point.
          ? "deployment { domain_id: " + std::to_string(domain) +
                " clock: REAL_TIME liveliness_timeout: 1 max_missed_answers: 300 "
                "command_watchdog_periods: 300 max_overrun_fraction: -1 }\n"
          : "deployment { domain_id: " + std::to_string(domain) + " }\n";
  std::ofstream(path) << "name: \"view_stays\"\n"
                         "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: "
                         "0.05 } }\n"
                         "motion { path: \"" +
                             kMotion +
                             "\" duration: 3 }\n"
                             "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
                             "substructuring { experimental_fraction: 0.3333333333333333 model { "
                             "linear {} } }\n" +
                             cases + deployment;
  return path.string();
}

// The probes' story: the last live answer, the first and last of the finished run, and whether
// every probe between those two was answered by it.
struct Story {
  std::optional<double> last_live_s, first_replay_s, last_replay_s;
  int replay_misses = 0;  // probes between the first and last finished answers that got another
};

Story story_of(const std::vector<Probe>& probes) {
  Story s;
  int misses_since_last_replay = 0;
  for (const Probe& p : probes) {
    if (p.answered && p.mode == "live" && !s.first_replay_s) s.last_live_s = p.at_s;
    if (p.answered && p.mode == "replay") {
      if (!s.first_replay_s) s.first_replay_s = p.at_s;
      s.last_replay_s = p.at_s;
      s.replay_misses += misses_since_last_replay;
      misses_since_last_replay = 0;
    } else if (s.first_replay_s) {
      ++misses_since_last_replay;
    }
  }
  return s;
}

TEST(LaunchView, ARealTimeRunsPageStaysForViewForSecondsThenLaunchExitsWithTheRunsStatus) {
  const auto dir = scratch("launch_view_stays");
  const int port = free_port();
  const int domain = test::scope_dds_to_this_test();
  test::StallWitness witness;
  const auto [exit, probes] =
      launch_and_probe(study(dir, "REAL_TIME", domain, "cases { name: \"reference\" }\n"), port,
                       {"--domain", std::to_string(domain), "--view-for", "10",
                        "--platform-seconds", "0.2", "--accept-platform"},
                       dir);
  const test::MeasuredPlatform machine = witness.finish();
  const std::string log = read_file(dir / "launch.log");
  // A failed run is put down to this machine only by the suite's one rule
  // (tests/support/real_time_run.h), from the run's own status and the witness beside it.
  // The code's own figure first: it never skips (tests/support/real_time_run.h).
  if (const auto burned = test::loop_cpu_over_bound(
          read_file(dir / "out" / "logs" / "reference" / "coordinator.log")))
    FAIL() << *burned;
  if (exit != 0) {
    const runtime::RecordContents record = runtime::read_record(dir / "out" / "reference.rthsrec");
    if (record.header() != nullptr && record.footer() != nullptr)
      if (const auto why =
              test::machine_stalled(record.footer()->status(), *record.header(), machine))
        GTEST_SKIP() << *why;
  }
  ASSERT_EQ(exit, 0) << log << "\nthe machine meanwhile: " << machine.text;
  const Story s = story_of(probes);
  ASSERT_TRUE(s.last_live_s) << "the live page never answered\n" << log;
  ASSERT_TRUE(s.first_replay_s) << "the finished run was never served\n" << log;
  const double gap = *s.first_replay_s - *s.last_live_s;
  std::cout << "# live until " << *s.last_live_s << " s, the finished run from "
            << *s.first_replay_s << " s to " << *s.last_replay_s << " s (hand-over " << gap
            << " s), " << probes.size() << " probes\n";
  EXPECT_EQ(s.replay_misses, 0);  // answered at every probe once it stayed
  EXPECT_GE(*s.last_replay_s - *s.first_replay_s, 9.5);
  EXPECT_LT(*s.last_replay_s - *s.first_replay_s, 60.0);  // then it went, and launch with it
  EXPECT_NE(log.find("rths launch: the view stays on the finished run of case reference at "
                     "http://127.0.0.1:" +
                     std::to_string(port) + "/ for 10 s from the run's end (or until Ctrl-C)"),
            std::string::npos)
      << log;
  const Probe& finished =
      *std::find_if(probes.rbegin(), probes.rend(), [](const Probe& p) { return p.answered; });
  EXPECT_EQ(finished.mode, "replay");
  // Within its verdict (tolerance off): "completed", or a warning naming its overruns or the
  // platform it was let run on; never failed.
  EXPECT_NE(finished.level, "failed") << finished.badge;
  EXPECT_EQ(finished.badge.rfind("completed", 0), 0u) << finished.badge;
}

// A lockstep case past its critical delay: its coordinator completes every step, launch judges
// it diverging against the lag-free run, the page stays showing that in red (not "completed"),
// and launch still exits 1 once the view has gone.
TEST(LaunchView, AFailedRunsPageShowsItsVerdictAndLaunchStillExitsNonZero) {
  const auto dir = scratch("launch_view_failed");
  const int port = free_port();
  const int domain = test::scope_dds_to_this_test();
  const auto [exit, probes] = launch_and_probe(
      study(dir, "LOCKSTEP", domain, "cases { name: \"late\" delay { shift { delay: 0.05 } } }\n"),
      port, {"--domain", std::to_string(domain), "--view-for", "2"}, dir);
  const std::string log = read_file(dir / "launch.log");
  EXPECT_EQ(exit, 1) << log;
  const Story s = story_of(probes);
  ASSERT_TRUE(s.first_replay_s) << log;
  EXPECT_EQ(s.replay_misses, 0);
  const auto last = std::find_if(probes.rbegin(), probes.rend(),
                                 [](const Probe& p) { return p.mode == "replay"; });
  EXPECT_EQ(last->badge.rfind("diverg", 0), 0u) << last->badge;
  EXPECT_EQ(last->level, "failed");
}

TEST(LaunchView, ViewForNeedsTheView) {
  const Outcome o =
      run("launch " + (kSource / "configs/paper_frame.textproto").string() + " --view-for 3");
  EXPECT_EQ(o.exit_code, 2) << o.output;
  EXPECT_NE(o.output.find("--view-for needs --view HOST:PORT"), std::string::npos) << o.output;
}

}  // namespace
}  // namespace rths::cli_test
