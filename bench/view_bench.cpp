// Live-view benchmark (not a test). Real-time runs at --rate Hz (coordinator in this process,
// substructure node and actuator emulator as child processes over Cyclone DDS on loopback), in
// pairs in one sitting: without the view, then with the view served and one headless Chromium
// showing the page. Prints per run and as medians of --repeat pairs:
//   overruns (% of steps) and wake-up to command written (median / p99, us);
//   this process's CPU time over the run (s; the difference is the view's: the feed's parsing on
//   the record's writer thread, the server's threads, the JSON);
//   this process's RSS at 10 / 50 / 95 % of the run (MB; flat = the view's rings are sized at
//   the start);
//   the browser's CPU time (s, user + system, summed over Chromium's process tree from
//   /proc/<pid>/stat, exited children included through their parent's cutime/cstime) over the
//   run, and as % of one core. Chromium starts before the run, which starts once the page has
//   opened its stream and settled: its start-up's CPU is in neither run.
// --page-query Q opens the page at URL?Q (e.g. fps=30: the page's draw rate cap).
// --browser-cpu N runs Chromium on CPU N alone (taskset) and both runs of a pair with the
// deployment's pin_loop on --loop-cpu (default: 1 if N is 0, else 0), the nodes kept off it as
// `rths launch` keeps them: the loop's CPU is then shared with nothing of the page's.
// Target: overruns with the view within +0.02 points of the run without it; wake-up
// to command unchanged. The view runs as `rths-coordinator --view` runs it: with the in-process
// prediction computed before the run (view::describe_run, outside the CPU window).
// --rss-minutes M instead makes one run of M minutes with the view and Chromium on its page (the
// 1979 record repeated end to end as a columns file, fail-safe windows widened to 300 periods so
// a loaded machine's stalls do not hold it) and samples this process's RSS every --rss-every s:
// prints each sample, the first and last minute's mean and the maximum (flat: the view's rings
// are sized at the header, so after the first minute nothing grows).
//   rths_view_bench [--seconds S] [--rate HZ] [--repeat N] [--domain D] [--no-browser]
//                   [--failsafe-periods N] [--page-query Q] [--browser-cpu N [--loop-cpu N]]
//   rths_view_bench --rss-minutes 10 [--rss-every 10] [--rate HZ] [--domain D]
// --hammer N instead runs triples: the loop without the view (bare), with the view served and no
// client (quiet), then with N clients looping on /api/snapshot as fast as they can, 200 idle
// connections kept open (each one the view closes is reopened at once), 8 that drip a
// header byte every 2 s and --churn C new connections a second (each held 1 s, every other one
// never sending; default 15); meanwhile a fresh client asks for GET / every 0.5 s (2 s
// timeouts) as a browser would. Prints the overruns of each run and their medians, the ratio
// hammered / quiet and hammered / bare, the fresh client's answers (served within 2 s / asked,
// slowest) and the snapshots served against those built (SnapshotCache's cap).
// --realtime-priority P puts, in every run, the loops and DDS receive threads of the run's
// processes on SCHED_FIFO P (the deployment's realtime_priority): they then preempt the view's
// threads and the clients whenever they wake, as on a lab machine set up for real time.
// --loop-cpu N with it pins the loop alone on CPU N (pin_loop) in all three runs: the view's
// threads and the clients, on the other CPUs, then take from the loop only what the kernel does
// for them on its CPU, as with clients on another machine.
//   rths_view_bench --hammer 8 [--churn C] [--loop-cpu N] [--realtime-priority P] [--seconds S]
//                   [--repeat N]
#include <netinet/in.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "bench/bench_support.h"
#include "coordinator/coordinator.h"
#include "runtime/launch/launch.h"
#include "runtime/record/measurements.h"
#include "runtime/record/record.h"
#include "transport/dds_endpoint.h"
#include "util/process.h"
#include "view/context.h"
#include "view/feed.h"
#include "view/server.h"

// After Eigen (through the headers above): <resolv.h>, which httplib includes, defines _res.
#include <httplib.h>

namespace {

using namespace rths;
using namespace std::chrono_literals;

// `motion`: a motion block; `failsafe`: the fail-safe windows in periods; `loop_cpu` >= 0: the
// loop thread pinned there alone (pin_loop); `fifo` > 0: the deployment's realtime_priority.
std::string study_text(double rate, const std::string& motion, int domain, int failsafe,
                       int loop_cpu, int fifo) {
  std::string pin = loop_cpu >= 0 ? " pin_loop: true loop_cpu: " + std::to_string(loop_cpu) : "";
  if (fifo > 0) pin += " realtime_priority: " + std::to_string(fifo);
  return bench::sdof_study_text(
      "view_bench", 1.0 / rate, motion,
      "deployment { domain_id: " + std::to_string(domain) +
          " clock: REAL_TIME max_overrun_fraction: -1 max_missed_answers: " +
          std::to_string(failsafe) + " command_watchdog_periods: " + std::to_string(failsafe) +
          pin + " }\n");
}

// The 1979 record repeated end to end to `seconds`, as a one-column file (m/s^2) in `dir`; its
// motion block.
std::string repeated_motion(double seconds, const std::filesystem::path& dir) {
  config::GroundMotion spec;
  spec.set_path(bench::imperial_valley_path());
  const core::GroundMotion record = study::load_motion(spec, {});
  const auto file = dir / "repeated_motion.txt";
  std::ofstream out(file);
  out.precision(17);
  const auto samples = static_cast<std::size_t>(std::ceil(seconds / record.dt)) + 1;
  for (std::size_t i = 0; i < samples; ++i)
    out << record.acceleration[i % record.acceleration.size()] << "\n";
  char dt[32];
  std::snprintf(dt, sizeof dt, "%.17g", record.dt);
  return "motion { path: \"" + file.string() + "\" format: COLUMNS column_dt: " + dt +
         " column_units: M_PER_S2 duration: " + std::to_string(seconds) + " }\n";
}

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// User + system CPU (s) of the process tree under `root`: each live process's utime + stime +
// cutime + cstime (the last two: its exited, reaped children), from /proc/<pid>/stat.
double tree_cpu_seconds(pid_t root) {
  std::map<pid_t, pid_t> parent;
  std::map<pid_t, double> ticks;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "stat");
    std::string line;
    if (!std::getline(in, line)) continue;  // gone meanwhile
    const auto close = line.rfind(')');     // the command name may hold spaces
    if (close == std::string::npos) continue;
    std::istringstream fields(line.substr(close + 2));
    std::vector<std::string> f;
    for (std::string v; fields >> v && f.size() < 15;) f.push_back(v);
    if (f.size() < 15) continue;
    // After the name: state(0) ppid(1) ... utime(11) stime(12) cutime(13) cstime(14).
    const auto pid = static_cast<pid_t>(std::stol(name));
    parent[pid] = static_cast<pid_t>(std::stol(f[1]));
    ticks[pid] = std::stod(f[11]) + std::stod(f[12]) + std::stod(f[13]) + std::stod(f[14]);
  }
  double sum = 0;
  for (const auto& [pid, t] : ticks) {
    pid_t p = pid;
    for (int depth = 0; p > 1 && p != root && depth < 64; ++depth)
      p = parent.count(p) ? parent[p] : 0;
    if (p == root) sum += t;
  }
  return sum / static_cast<double>(sysconf(_SC_CLK_TCK));
}

double rss_mb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1;
}

struct Spec {
  std::string name;
  double rate = 1024, seconds = 20;
  int domain = 215, failsafe = 30;
  bool with_view = false, browser = false;
  double rss_every = 0;          // s between RSS samples; 0: at 10, 50 and 95 % of the run
  std::string page_query;        // appended to the page's URL after '?'
  int browser_cpu = -1;          // >= 0: Chromium on this CPU alone (taskset)
  int loop_cpu = -1;             // >= 0: the deployment's pin_loop on this CPU
  int realtime_priority = 0;     // > 0: the deployment's realtime_priority (SCHED_FIFO)
  int hammer = 0;                // > 0: clients looping on /api/snapshot, and the idle crowd
  int churn = 15;                // with hammer: new connections a second
  int snapshot_period_ms = 200;  // the view's snapshot cap (0: rebuilt for every request)
};

struct Figures {
  double overrun_pct = 0, latency_median_us = 0, latency_p99_us = 0, cpu_s = 0;
  std::vector<std::pair<double, double>> rss;  // (s into the run, MB)
  std::string status;
  std::uint64_t streams_served = 0, updates_sent = 0;  // the view's, to the browser
  std::uint64_t snapshots_served = 0, snapshot_builds = 0;
  int fresh_asked = 0, fresh_served = 0;  // the fresh client's GET / (served within 2 s)
  double fresh_slowest_ms = 0;
  double browser_cpu_s = 0, browser_window_s = 0;  // Chromium's CPU over that wall time
};

// Chromium's CPU from the run's start (its page already open) until `done`.
std::thread browser_cpu_sampler(pid_t chromium, Figures& f, const std::atomic<bool>& done) {
  return std::thread([chromium, &f, &done] {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = tree_cpu_seconds(chromium);
    while (!done) std::this_thread::sleep_for(20ms);
    f.browser_cpu_s = tree_cpu_seconds(chromium) - c0;
    f.browser_window_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  });
}

// Samples this process's RSS while the run goes, until `done`.
std::thread rss_sampler(const Spec& spec, std::vector<std::pair<double, double>>& out,
                        const std::atomic<bool>& done) {
  return std::thread([&spec, &out, &done] {
    const auto start = std::chrono::steady_clock::now();
    const auto since = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    // At 10, 50 and 95 % of the run, or every rss_every s until it ends (a run that falls
    // behind real time lasts longer than spec.seconds).
    std::vector<double> at = {0.1 * spec.seconds, 0.5 * spec.seconds, 0.95 * spec.seconds};
    for (std::size_t i = 0; i < at.size() || spec.rss_every > 0; ++i) {
      const double t = spec.rss_every > 0 ? spec.rss_every * static_cast<double>(i + 1) : at[i];
      while (!done && since() < t) std::this_thread::sleep_for(20ms);
      if (done) return;
      out.emplace_back(since(), rss_mb());
      if (spec.rss_every > 0)
        std::printf("  %6.0f s  RSS %.1f MB\n", out.back().first, out.back().second);
      std::fflush(stdout);
    }
  });
}

// Clients the view should shrug off, while the run goes: `clients` threads looping on
// /api/snapshot, 200 idle connections kept open (each one closed is reopened at once), 8
// that drip a header byte every 2 s and `churn` new connections a second; and a fresh client
// asking for the page every 0.5 s, whose answers are counted (fresh()).
class Hammer {
 public:
  Hammer(int port, int clients, int churn) {
    threads_.emplace_back([this, port] { hold_idle(port); });
    for (int i = 0; i < 8; ++i) threads_.emplace_back([this, port] { drip(port); });
    if (churn > 0) threads_.emplace_back([this, port, churn] { churn_connections(port, churn); });
    for (int i = 0; i < clients; ++i)
      threads_.emplace_back([this, port] {
        // At nice 19, as clients on another machine would be: what the view's serving costs the
        // loop is then measured, not the clients' own CPU (they share this machine's cores).
        view::set_thread_nice(19);
        httplib::Client client("127.0.0.1", port);
        while (!done_) client.Get("/api/snapshot");
      });
    threads_.emplace_back([this, port] { ask_as_a_browser(port); });
  }
  ~Hammer() {
    done_ = true;
    for (auto& t : threads_) t.join();
  }
  // The fresh client's GET /: asked, answered 200 within 2 s, the slowest answer (ms).
  void fresh(Figures& f) const {
    std::lock_guard lock(mutex_);
    f.fresh_asked = asked_;
    f.fresh_served = served_;
    f.fresh_slowest_ms = slowest_ms_;
  }

 private:
  static int connect_to(int port) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    return fd;
  }
  void hold_idle(int port) {
    view::set_thread_nice(19);
    std::vector<pollfd> crowd;
    for (int i = 0; i < 200; ++i) crowd.push_back({connect_to(port), POLLIN, 0});
    while (!done_) {
      poll(crowd.data(), crowd.size(), 50);
      for (pollfd& c : crowd) {
        if (c.revents == 0) continue;
        close(c.fd);  // closed by the view (displaced, or a 408 at its deadline)
        c = {connect_to(port), POLLIN, 0};
      }
    }
    for (const pollfd& c : crowd) close(c.fd);
  }
  void drip(int port) {
    while (!done_) {
      const int fd = connect_to(port);
      for (int k = 0; k < 30 && !done_; ++k) {
        if (send(fd, "G", 1, MSG_NOSIGNAL) != 1) break;  // closed by the view: connect again
        for (int w = 0; w < 40 && !done_; ++w) std::this_thread::sleep_for(50ms);
      }
      close(fd);
    }
  }
  // `per_second` new connections, each held 1 s; every other one sends a whole request.
  void churn_connections(int port, int per_second) {
    view::set_thread_nice(19);
    const std::string request =
        "GET /api/health HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n";
    std::deque<int> open;
    for (int k = 0; !done_; ++k) {
      const int fd = connect_to(port);
      if (k % 2 == 1) (void)!send(fd, request.data(), request.size(), MSG_NOSIGNAL);
      open.push_back(fd);
      if (open.size() > static_cast<std::size_t>(per_second)) {
        close(open.front());
        open.pop_front();
      }
      std::this_thread::sleep_for(std::chrono::microseconds(1000000 / per_second));
    }
    for (const int fd : open) close(fd);
  }
  void ask_as_a_browser(int port) {
    while (!done_) {
      const auto start = std::chrono::steady_clock::now();
      httplib::Client client("127.0.0.1", port);
      client.set_connection_timeout(2s);
      client.set_read_timeout(2s);
      const auto page = client.Get("/");
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      {
        std::lock_guard lock(mutex_);
        ++asked_;
        if (page && page->status == 200 && ms <= 2000) ++served_;
        slowest_ms_ = std::max(slowest_ms_, ms);
      }
      for (int w = 0; w < 10 && !done_; ++w) std::this_thread::sleep_for(50ms);
    }
  }
  std::atomic<bool> done_{false};
  std::vector<std::thread> threads_;
  mutable std::mutex mutex_;
  int asked_ = 0, served_ = 0;
  double slowest_ms_ = 0;
};

// The view as the coordinator program serves it, and one headless Chromium on its page.
struct View {
  view::Feed feed;
  std::unique_ptr<view::ViewServer> server;
  std::optional<util::ChildProcess> chromium;
  std::optional<Hammer> hammer;
  View(const study::PreparedStudy& prepared, const std::filesystem::path& dir, const Spec& spec) {
    view::describe_run(feed, prepared, "");
    view::ServerOptions loopback_any_port;
    loopback_any_port.address = view::ListenAddress{"127.0.0.1", 0};
    loopback_any_port.snapshot_period = std::chrono::milliseconds(spec.snapshot_period_ms);
    server = std::make_unique<view::ViewServer>(feed, std::move(loopback_any_port));
    if (spec.hammer > 0) hammer.emplace(server->port(), spec.hammer, spec.churn);
    if (!spec.browser) return;
    const auto profile = dir / "chromium_profile";
    std::filesystem::remove_all(profile);
    util::ChildOptions options;
    if (spec.browser_cpu >= 0) options.prefix = {"taskset", "-c", std::to_string(spec.browser_cpu)};
    const std::string url = server->url() + (spec.page_query.empty() ? "" : "?" + spec.page_query);
    chromium.emplace(
        "/usr/bin/chromium",
        std::vector<std::string>{"--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                                 "--no-first-run", "--disable-background-networking",
                                 "--disable-component-update", "--disable-sync",
                                 "--user-data-dir=" + profile.string(), url},
        dir / "chromium.log", options);
    wait_for_page();
  }

  // Chromium's start-up takes seconds of CPU: the run starts once the page has opened its stream
  // and settled (1 s more), so neither the run nor the browser's figure includes it.
  void wait_for_page() const {
    const auto until = std::chrono::steady_clock::now() + 60s;
    while (server->counters()["streams_served"] == 0) {
      if (std::chrono::steady_clock::now() > until)
        throw std::runtime_error("Chromium did not open the page within 60 s (see its log)");
      std::this_thread::sleep_for(50ms);
    }
    std::this_thread::sleep_for(1s);
  }
};

void measure_record(const std::filesystem::path& record, const coordinator::RunOutcome& outcome,
                    Figures& f) {
  std::vector<double> latency;
  for (const auto* s : runtime::read_record(record).steps())
    if (s->step() > 0) latency.push_back(s->command_latency());
  const auto summary = runtime::summarize(latency);
  const auto steps = outcome.counters.steps();
  f.overrun_pct =
      steps ? 100.0 * static_cast<double>(outcome.counters.overruns()) / static_cast<double>(steps)
            : 0;
  f.latency_median_us = summary.median * 1e6;
  f.latency_p99_us = summary.p99 * 1e6;
  f.status = outcome.status;
}

Figures run(const Spec& spec) {
  const std::string directory = "rths_view_bench_" + spec.name;
  const auto dir = std::filesystem::temp_directory_path() / directory;
  std::filesystem::create_directories(dir);
  const std::string motion = spec.seconds > 35 ? repeated_motion(spec.seconds, dir)
                                               : bench::imperial_valley_motion(spec.seconds);
  std::optional<View> view;  // outlives the coordinator, which feeds it
  bench::DistributedRun distributed(
      {.directory = directory,
       .run_id = "view-bench-" + spec.name,
       .study_text = study_text(spec.rate, motion, spec.domain, spec.failsafe, spec.loop_cpu,
                                spec.realtime_priority),
       .domain = spec.domain,
       .nodes = {},
       .keep_off_loop_cpu = spec.loop_cpu >= 0});
  coordinator::CoordinatorOptions options;
  if (spec.with_view) {
    view.emplace(distributed.prepared(), dir, spec);
    options.record_observer = &view->feed;
  }
  coordinator::Coordinator& coordinator = distributed.start(options);
  Figures f;
  std::atomic<bool> done{false};
  std::thread sampler = rss_sampler(spec, f.rss, done);
  std::thread browser_sampler;
  if (view && view->chromium) browser_sampler = browser_cpu_sampler(view->chromium->pid(), f, done);
  const double cpu0 = cpu_seconds();
  const auto outcome = coordinator.run();
  f.cpu_s = cpu_seconds() - cpu0;
  done = true;
  sampler.join();
  if (browser_sampler.joinable()) browser_sampler.join();
  if (view) {
    const nlohmann::json counters = view->server->counters();
    f.streams_served = counters["streams_served"];
    f.updates_sent = counters["updates_sent"];
    f.snapshots_served = counters["snapshots_served"];
    f.snapshot_builds = counters["snapshot_builds"];
    if (view->hammer) view->hammer->fresh(f);
    view->hammer.reset();
    spdlog::info("{}: view counters {}", spec.name, counters.dump());
    view->server->shutdown();
    if (view->chromium) view->chromium->terminate();
  }
  distributed.wait_for_nodes();
  if (!outcome.ok) spdlog::warn("{}: {}", spec.name, outcome.status);
  measure_record(distributed.record(), outcome, f);
  std::filesystem::remove(distributed.record());
  return f;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

double browser_pct(const Figures& f) {
  return f.browser_window_s > 0 ? 100.0 * f.browser_cpu_s / f.browser_window_s : 0;
}

void print(const char* label, const Figures& f) {
  std::printf("  %-9s overruns %.3f %%  wake-up to command %.1f / %.1f us  CPU %.2f s  RSS", label,
              f.overrun_pct, f.latency_median_us, f.latency_p99_us, f.cpu_s);
  for (const auto& [t, mb] : f.rss) std::printf(" %.1f", mb);
  std::printf(" MB  (%s; %llu updates sent to %llu page(s))\n", f.status.c_str(),
              static_cast<unsigned long long>(f.updates_sent),
              static_cast<unsigned long long>(f.streams_served));
  if (f.browser_window_s > 0)
    std::printf("            browser CPU %.2f s in %.1f s (%.1f %% of a core)\n", f.browser_cpu_s,
                f.browser_window_s, browser_pct(f));
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

// Pairs of runs without and with the view; medians.
void pairs(Spec spec, int repeat, bool browser) {
  std::vector<double> off_overruns, on_overruns, off_latency, on_latency, off_cpu, on_cpu,
      browser_cpu;
  for (int i = 0; i < repeat; ++i) {
    spec.name = "off_" + std::to_string(i);
    spec.with_view = spec.browser = false;
    const Figures off = run(spec);
    spec.name = "on_" + std::to_string(i);
    spec.with_view = true;
    spec.browser = browser;
    const Figures on = run(spec);
    std::printf("pair %d (%g Hz, %g s, load average %s):\n", i + 1, spec.rate, spec.seconds,
                load_average().c_str());
    print("no view", off);
    print(browser ? "view+page" : "view", on);
    off_overruns.push_back(off.overrun_pct);
    on_overruns.push_back(on.overrun_pct);
    off_latency.push_back(off.latency_median_us);
    on_latency.push_back(on.latency_median_us);
    off_cpu.push_back(off.cpu_s);
    on_cpu.push_back(on.cpu_s);
    browser_cpu.push_back(browser_pct(on));
    std::fflush(stdout);
  }
  std::printf(
      "=> medians of %d: overruns %.3f %% without the view, %.3f %% with it (%+.3f points; "
      "target <= +0.02); wake-up to command %.1f / %.1f us; the view's CPU %.2f s in %g s "
      "(%.1f %% of a core)\n",
      repeat, median(off_overruns), median(on_overruns), median(on_overruns) - median(off_overruns),
      median(off_latency), median(on_latency), median(on_cpu) - median(off_cpu), spec.seconds,
      100.0 * (median(on_cpu) - median(off_cpu)) / spec.seconds);
  if (browser)
    std::printf("   the browser's CPU %.1f %% of a core (median; page %s%s%s)\n",
                median(browser_cpu), spec.page_query.empty() ? "as served" : "?",
                spec.page_query.c_str(), spec.browser_cpu >= 0 ? ", Chromium pinned" : "");
}

// Triples of runs: the bare loop, with the view and no client, with the view hammered; medians
// and the ratios.
void hammer_triples(Spec spec, int repeat, int clients) {
  std::vector<double> bare_overruns, quiet_overruns, hammered_overruns, bare_latency, quiet_latency,
      hammered_latency;
  int asked = 0, served = 0;
  double slowest = 0;
  for (int i = 0; i < repeat; ++i) {
    spec.browser = false;
    spec.hammer = 0;
    spec.name = "bare_" + std::to_string(i);
    spec.with_view = false;
    const Figures bare = run(spec);
    spec.name = "quiet_" + std::to_string(i);
    spec.with_view = true;
    const Figures quiet = run(spec);
    spec.name = "hammered_" + std::to_string(i);
    spec.hammer = clients;
    const Figures hammered = run(spec);
    std::printf("triple %d (%g Hz, %g s, snapshot cap every %d ms, load average %s):\n", i + 1,
                spec.rate, spec.seconds, spec.snapshot_period_ms, load_average().c_str());
    print("bare", bare);
    print("quiet", quiet);
    print("hammered", hammered);
    std::printf(
        "            %llu snapshots served from %llu builds; a fresh GET / served within "
        "2 s %d of %d times (slowest %.0f ms)\n",
        static_cast<unsigned long long>(hammered.snapshots_served),
        static_cast<unsigned long long>(hammered.snapshot_builds), hammered.fresh_served,
        hammered.fresh_asked, hammered.fresh_slowest_ms);
    bare_overruns.push_back(bare.overrun_pct);
    quiet_overruns.push_back(quiet.overrun_pct);
    hammered_overruns.push_back(hammered.overrun_pct);
    bare_latency.push_back(bare.latency_median_us);
    quiet_latency.push_back(quiet.latency_median_us);
    hammered_latency.push_back(hammered.latency_median_us);
    asked += hammered.fresh_asked;
    served += hammered.fresh_served;
    slowest = std::max(slowest, hammered.fresh_slowest_ms);
    std::fflush(stdout);
  }
  const double bare = median(bare_overruns), quiet = median(quiet_overruns),
               hammered = median(hammered_overruns);
  std::printf(
      "=> medians of %d: overruns %.3f %% bare, %.3f %% with the view alone, %.3f %% with %d "
      "clients looping on /api/snapshot, the idle crowd and %d connections a second (ratio to "
      "the view alone %.2f, to the bare loop %.2f); wake-up to command %.1f / %.1f / %.1f us; a "
      "fresh GET / served within 2 s %d of %d times (slowest %.0f ms)\n",
      repeat, bare, quiet, hammered, clients, spec.churn, quiet > 0 ? hammered / quiet : 0.0,
      bare > 0 ? hammered / bare : 0.0, median(bare_latency), median(quiet_latency),
      median(hammered_latency), served, asked, slowest);
}

double mean_between(const std::vector<std::pair<double, double>>& rss, double from, double to) {
  double sum = 0;
  int n = 0;
  for (const auto& [t, mb] : rss)
    if (t >= from && t < to) sum += mb, ++n;
  return n ? sum / n : 0;
}

// One long run with the view and a browser: RSS over time.
void rss_run(Spec spec, bool browser) {
  spec.name = "rss";
  spec.with_view = true;
  spec.browser = browser;
  spec.failsafe = 300;
  std::printf("%g min at %g Hz with the view%s, RSS every %g s (load average %s):\n",
              spec.seconds / 60, spec.rate, browser ? " and Chromium on its page" : "",
              spec.rss_every, load_average().c_str());
  std::fflush(stdout);
  const Figures f = run(spec);
  double peak = 0;
  for (const auto& [t, mb] : f.rss) peak = std::max(peak, mb);
  const double end = f.rss.empty() ? 0 : f.rss.back().first;
  const double first = mean_between(f.rss, 0, 60);
  const double last = mean_between(f.rss, end - 60 + 1e-9, end + 1);
  std::printf(
      "=> RSS first minute %.1f MB, last minute %.1f MB (%+.1f MB), max %.1f MB over %zu "
      "samples in %.0f s; overruns %.3f %%, wake-up to command %.1f / %.1f us, CPU %.1f s (%s; "
      "%llu updates sent to %llu page(s); load average %s)\n",
      first, last, last - first, peak, f.rss.size(), end, f.overrun_pct, f.latency_median_us,
      f.latency_p99_us, f.cpu_s, f.status.c_str(), static_cast<unsigned long long>(f.updates_sent),
      static_cast<unsigned long long>(f.streams_served), load_average().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rths_view_bench: real time with and without the live view (not a test)"};
  Spec spec;
  spec.seconds = 30;
  int repeat = 3;
  double rss_minutes = 0;
  bool no_browser = false;
  app.add_option("--seconds", spec.seconds, "s of test per run");
  app.add_option("--rate", spec.rate, "integrator rate (Hz)");
  app.add_option("--repeat", repeat, "pairs of runs (medians over them)");
  app.add_option("--domain", spec.domain, "DDS domain id");
  app.add_flag("--no-browser", no_browser, "serve the view but connect no browser");
  app.add_option("--failsafe-periods", spec.failsafe,
                 "the pairs' fail-safe windows (answers, command watchdog) in periods; wider "
                 "keeps a loaded machine's stalls from holding runs early")
      ->default_val(30)
      ->check(CLI::Range(3, 1000));
  app.add_option("--rss-minutes", rss_minutes,
                 "instead of the pairs: one run this long with the view, sampling RSS")
      ->check(CLI::Range(1.0, 120.0));
  app.add_option("--rss-every", spec.rss_every, "s between RSS samples of --rss-minutes")
      ->default_val(10.0)
      ->check(CLI::Range(1.0, 600.0));
  app.add_option("--page-query", spec.page_query, "opens the page at URL?Q, e.g. fps=30");
  app.add_option("--browser-cpu", spec.browser_cpu,
                 "Chromium on this CPU alone (taskset); the loop pinned alone on --loop-cpu")
      ->check(CLI::Range(0, 1023));
  app.add_option("--loop-cpu", spec.loop_cpu,
                 "with --browser-cpu: the deployment's loop_cpu (default 1 if the browser's is 0, "
                 "else 0); with --hammer: the loop alone on this CPU, the view's threads and the "
                 "clients off it, as clients on another machine would be")
      ->check(CLI::Range(0, 1023));
  int hammer = 0;
  app.add_option("--hammer", hammer,
                 "instead: pairs with the view, without and with N clients looping on "
                 "/api/snapshot and an idle crowd")
      ->check(CLI::Range(1, 64));
  app.add_option("--realtime-priority", spec.realtime_priority,
                 "the deployment's realtime_priority in every run: the loops and DDS receive "
                 "threads of the run's processes on SCHED_FIFO at this priority (1-98)")
      ->check(CLI::Range(1, 98));
  app.add_option("--churn", spec.churn,
                 "with --hammer: new connections a second, every other one never sending")
      ->default_val(15)
      ->check(CLI::Range(0, 1000));
  app.add_option("--snapshot-period-ms", spec.snapshot_period_ms,
                 "the view's snapshot cap (0: rebuilt for every request, as before the cap)")
      ->default_val(200)
      ->check(CLI::Range(0, 10000));
  CLI11_PARSE(app, argc, argv);
  if (spec.browser_cpu >= 0 && spec.loop_cpu < 0) spec.loop_cpu = spec.browser_cpu == 0 ? 1 : 0;
  if (spec.loop_cpu >= 0 && spec.browser_cpu < 0 && hammer == 0) {
    std::fprintf(stderr, "--loop-cpu %d needs --browser-cpu or --hammer\n", spec.loop_cpu);
    return 2;
  }
  if (spec.loop_cpu >= 0 && spec.loop_cpu == spec.browser_cpu) {
    std::fprintf(stderr, "--loop-cpu %d: must differ from --browser-cpu %d\n", spec.loop_cpu,
                 spec.browser_cpu);
    return 2;
  }
  runtime::ensure_dds_config();
  spdlog::set_level(spdlog::level::warn);
  const bool browser = !no_browser && std::filesystem::exists("/usr/bin/chromium");
  if (hammer > 0) {
    hammer_triples(spec, repeat, hammer);
  } else if (rss_minutes > 0) {
    spec.seconds = rss_minutes * 60;
    rss_run(spec, browser);
  } else {
    spec.rss_every = 0;
    pairs(spec, repeat, browser);
  }
  return 0;
}
