// Live-view benchmark (not a test). Real-time runs at --rate Hz (coordinator in this process,
// substructure node and actuator emulator as child processes over Cyclone DDS on loopback), in
// pairs in one sitting: without the view, then with the view served and one headless Chromium
// showing the page. Prints per run and as medians of --repeat pairs:
//   overruns (% of steps) and wake-up to command written (median / p99, us);
//   this process's CPU time over the run (s; the difference is the view's: the feed's parsing on
//   the record's writer thread, the server's threads, the JSON);
//   this process's RSS at 10 / 50 / 95 % of the run (MB; flat = the view's rings are sized at
//   the start).
// Target: overruns with the view within +0.02 points of the run without it; wake-up
// to command unchanged.
//   rths_view_bench [--seconds S] [--rate HZ] [--repeat N] [--domain D] [--no-browser]
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <thread>

#include "bench/bench_support.h"
#include "runtime/measurements.h"
#include "runtime/record.h"
#include "view/feed.h"
#include "view/server.h"

namespace {

using namespace rths;
using namespace std::chrono_literals;

std::string study_text(double rate, double seconds, int domain) {
  return bench::sdof_study_text("view_bench", 1.0 / rate, bench::imperial_valley_motion(seconds),
                                "deployment { domain_id: " + std::to_string(domain) +
                                    " clock: REAL_TIME max_overrun_fraction: -1 "
                                    "max_missed_answers: 30 command_watchdog_periods: 30 }\n");
}

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double rss_mb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

struct Figures {
  double overrun_pct = 0, latency_median_us = 0, latency_p99_us = 0, cpu_s = 0;
  std::vector<double> rss_mb;  // at 10, 50, 95 % of the run
  std::string browser;
};

// Samples this process's RSS at 10, 50 and 95 % of `seconds` while the run goes.
std::thread rss_sampler(double seconds, std::vector<double>& out, const std::atomic<bool>& done) {
  return std::thread([seconds, &out, &done] {
    const auto start = std::chrono::steady_clock::now();
    for (double at : {0.1, 0.5, 0.95}) {
      while (!done &&
             std::chrono::steady_clock::now() - start < std::chrono::duration<double>(at * seconds))
        std::this_thread::sleep_for(20ms);
      if (!done) out.push_back(rss_mb());
    }
  });
}

Figures run(const std::string& name, double rate, double seconds, int domain, bool with_view,
            bool browser) {
  view::Feed feed;  // outlives the coordinator, which feeds it
  bench::DistributedRun distributed({.directory = "rths_view_bench_" + name,
                                     .run_id = "view-bench-" + name,
                                     .study_text = study_text(rate, seconds, domain),
                                     .domain = domain,
                                     .nodes = {},
                                     .keep_off_loop_cpu = false});
  const auto& dir = distributed.dir();
  coordinator::CoordinatorOptions options;
  std::unique_ptr<view::ViewServer> server;
  std::optional<runtime::ChildProcess> chromium;
  Figures f;
  if (with_view) {
    options.record_observer = &feed;
    view::ServerOptions loopback_any_port;
    loopback_any_port.address = view::ListenAddress{"127.0.0.1", 0};
    server = std::make_unique<view::ViewServer>(feed, std::move(loopback_any_port));
    if (browser) {
      const auto profile = dir / "chromium_profile";
      std::filesystem::remove_all(profile);
      chromium.emplace(
          "/usr/bin/chromium",
          std::vector<std::string>{"--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                                   "--no-first-run", "--disable-background-networking",
                                   "--disable-component-update", "--disable-sync",
                                   "--user-data-dir=" + profile.string(), server->url()},
          dir / "chromium.log");
      f.browser = "chromium";
    }
  }
  coordinator::Coordinator& coordinator = distributed.start(options);
  std::atomic<bool> done{false};
  std::thread sampler = rss_sampler(seconds, f.rss_mb, done);
  const double cpu0 = cpu_seconds();
  const auto outcome = coordinator.run();
  f.cpu_s = cpu_seconds() - cpu0;
  done = true;
  sampler.join();
  if (server) {
    spdlog::info("{}: view counters {}", name, server->counters().dump());
    server->shutdown();
  }
  if (chromium) chromium->terminate();
  distributed.wait_for_nodes();
  if (!outcome.ok) spdlog::warn("{}: {}", name, outcome.status);
  std::vector<double> latency;
  for (const auto* s : runtime::read_record(distributed.record()).steps())
    if (s->step() > 0) latency.push_back(s->command_latency());
  const auto summary = runtime::summarize(latency);
  const auto steps = outcome.counters.steps();
  f.overrun_pct =
      steps ? 100.0 * static_cast<double>(outcome.counters.overruns()) / static_cast<double>(steps)
            : 0;
  f.latency_median_us = summary.median * 1e6;
  f.latency_p99_us = summary.p99 * 1e6;
  return f;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

void print(const char* label, const Figures& f) {
  std::printf("  %-9s overruns %.3f %%  wake-up to command %.1f / %.1f us  CPU %.2f s  RSS", label,
              f.overrun_pct, f.latency_median_us, f.latency_p99_us, f.cpu_s);
  for (double r : f.rss_mb) std::printf(" %.1f", r);
  std::printf(" MB\n");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rths_view_bench: real time with and without the live view (not a test)"};
  double seconds = 30, rate = 1024;
  int repeat = 3, domain = 215;
  bool no_browser = false;
  app.add_option("--seconds", seconds, "s of test per run");
  app.add_option("--rate", rate, "integrator rate (Hz)");
  app.add_option("--repeat", repeat, "pairs of runs (medians over them)");
  app.add_option("--domain", domain, "DDS domain id");
  app.add_flag("--no-browser", no_browser, "serve the view but connect no browser");
  CLI11_PARSE(app, argc, argv);
  runtime::ensure_dds_config();
  spdlog::set_level(spdlog::level::warn);
  const bool browser = !no_browser && std::filesystem::exists("/usr/bin/chromium");
  std::vector<double> off_overruns, on_overruns, off_latency, on_latency, off_cpu, on_cpu;
  for (int i = 0; i < repeat; ++i) {
    const Figures off = run("off_" + std::to_string(i), rate, seconds, domain, false, false);
    const Figures on = run("on_" + std::to_string(i), rate, seconds, domain, true, browser);
    std::printf("pair %d (%g Hz, %g s):\n", i + 1, rate, seconds);
    print("no view", off);
    print(browser ? "view+page" : "view", on);
    off_overruns.push_back(off.overrun_pct);
    on_overruns.push_back(on.overrun_pct);
    off_latency.push_back(off.latency_median_us);
    on_latency.push_back(on.latency_median_us);
    off_cpu.push_back(off.cpu_s);
    on_cpu.push_back(on.cpu_s);
    std::fflush(stdout);
  }
  std::printf(
      "=> medians of %d: overruns %.3f %% without the view, %.3f %% with it (%+.3f points; "
      "target <= +0.02); wake-up to command %.1f / %.1f us; the view's CPU %.2f s in %g s "
      "(%.1f %% of a core)\n",
      repeat, median(off_overruns), median(on_overruns), median(on_overruns) - median(off_overruns),
      median(off_latency), median(on_latency), median(on_cpu) - median(off_cpu), seconds,
      100.0 * (median(on_cpu) - median(off_cpu)) / seconds);
  return 0;
}
