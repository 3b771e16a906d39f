// Run-secret benchmark (not a test): what the run secret's MACs cost real runs, and what a flood
// of forged messages costs a real-time run that has one. The coordinator runs in this process,
// the substructure node and actuator emulator as child processes over Cyclone DDS on loopback.
//   --secret-pairs: pairs without and with the run secret (nodes --insecure without), alternating:
//     lockstep steps/s (the 39 s record at 1 ms, every process on one CPU as `rths launch` places
//     lockstep runs) and 1024 Hz wake-up to command median (--seconds of record). Medians, ratios.
//   --flood-pairs: pairs of 1024 Hz runs with the run secret, without and with a hostile writer
//     (in this process, at nice 19) flooding node 1's answer topic with forged answers as fast as
//     it can: overruns (%), wake-up to command, forged messages sent per second and dropped
//     (the footer's unauthenticated count). Medians, the overruns' ratio.
//   rths_secret_bench --secret-pairs|--flood-pairs [--repeat N] [--seconds S] [--domain D]
//                     [--flood-rate PER_S]
// Domains D (lockstep) and D + 1 (real time), default 195.
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>

#include "bench/bench_support.h"
#include "runtime/record/record.h"
#include "transport/dds_endpoint.h"
#include "util/process.h"

namespace {

using namespace rths;

struct Args {
  int repeat = 3, domain = 195;
  double seconds = 10;
  double flood_rate = 0;  // forged messages per second; 0: as fast as the writer goes
};

constexpr const char* kUnjudged =
    "max_overrun_fraction: -1 min_answer_fraction: -1 max_missed_answers: 1000 "
    "command_watchdog_periods: 1000 ";

std::string study_text(double dt, double seconds, const std::string& deployment) {
  return bench::sdof_study_text("bench", dt, bench::imperial_valley_motion(seconds), deployment);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

struct Figures {
  double steps_per_second = 0, command_median_us = 0, overruns_pct = 0;
  std::uint64_t unauthenticated = 0;
};

// One run as the benches run them; `one_cpu`: this process and the nodes on one CPU.
Figures run(int domain, const std::string& text, const std::string& name, bool one_cpu,
            bool secret) {
  std::unique_ptr<util::ScopedCpuPin> pin;
  if (one_cpu) pin = std::make_unique<util::ScopedCpuPin>();
  bench::DistributedRun distributed({.directory = "rths_secret_bench_" + name,
                                     .run_id = "secret-bench-" + name,
                                     .study_text = text,
                                     .domain = domain,
                                     .nodes = {},
                                     .keep_off_loop_cpu = true,
                                     .run_secret = secret});
  const auto outcome = distributed.start({}).run();
  if (!outcome.ok) throw std::runtime_error(name + ": " + outcome.status);
  distributed.wait_for_nodes();
  std::vector<double> command;
  double walls = 0;
  std::size_t steps = 0;
  for (const auto* s : runtime::read_record(distributed.record()).steps()) {
    if (s->step() == 0) continue;
    command.push_back(s->command_latency());
    walls += s->step_wall();
    ++steps;
  }
  Figures f;
  f.steps_per_second = static_cast<double>(steps) / walls;
  f.command_median_us = median(command) * 1e6;
  f.overruns_pct = 100.0 * static_cast<double>(outcome.counters.overruns()) /
                   static_cast<double>(std::max<std::size_t>(steps, 1));
  f.unauthenticated = outcome.counters.unauthenticated();
  std::filesystem::remove(distributed.record());
  return f;
}

// Pairs without and with the run secret, alternating, in one sitting: what the MACs cost a
// lockstep step and a 1024 Hz step's wake-up to command.
void secret_pairs(const Args& a) {
  std::vector<double> lock_off, lock_on, command_off, command_on;
  const std::string rt = study_text(
      1.0 / 1024, a.seconds, std::string("deployment { clock: REAL_TIME ") + kUnjudged + "}");
  for (int r = 0; r < a.repeat; ++r)
    for (const bool secret : {false, true}) {
      const std::string tag = std::string(secret ? "_mac" : "_plain") + std::to_string(r);
      const auto lock = run(a.domain, study_text(0.001, 39.0, ""), "lockstep" + tag, true, secret);
      const auto paced = run(a.domain + 1, rt, "rt1024" + tag, false, secret);
      (secret ? lock_on : lock_off).push_back(lock.steps_per_second);
      (secret ? command_on : command_off).push_back(paced.command_median_us);
      std::printf("%s: lockstep %.0f steps/s; 1024 Hz wake-up to command median %.1f us\n",
                  secret ? "run secret" : "no secret ", lock.steps_per_second,
                  paced.command_median_us);
      std::fflush(stdout);
    }
  const auto m = [](const std::vector<double>& v) { return median(v); };
  std::printf(
      "  => medians of %d pairs: lockstep %.0f steps/s without the secret, %.0f with it (ratio "
      "%.3f); 1024 Hz wake-up to command %.1f us without, %.1f us with (ratio %.3f)\n",
      a.repeat, m(lock_off), m(lock_on), m(lock_on) / m(lock_off), m(command_off), m(command_on),
      m(command_on) / m(command_off));
}

// A hostile writer on node 1's answer topic of `domain`: forged answers (no MAC: it has no run
// secret) as fast as it can write them, or at `rate` per second (> 0: in bursts of 100), at
// nice 19 (as from another machine: the measurement is what the drops cost the coordinator, not
// the flooder's own CPU on this one), until destroyed.
class Flood {
 public:
  Flood(int domain, double rate)
      : writer_({static_cast<std::uint32_t>(domain), false, 1, "rths", 64, {}, {}}) {
    thread_ = std::thread([this, rate] {
      const auto start = std::chrono::steady_clock::now();
      setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 19);
      transport::Message m;
      m.run_id = "forged";
      m.node_id = 1;
      m.kind = 6;
      m.payload.assign(48, '\x2a');
      for (std::int64_t k = 0; !done_; ++k) {
        m.step = k;
        writer_.send(m);
        ++sent_;
        if (rate > 0 && k % 100 == 99)
          std::this_thread::sleep_until(
              start + std::chrono::duration<double>(static_cast<double>(k + 1) / rate));
      }
    });
  }
  ~Flood() {
    done_ = true;
    thread_.join();
  }
  std::uint64_t sent() const { return sent_; }

 private:
  transport::DdsEndpoint writer_;
  std::atomic<bool> done_{false};
  std::atomic<std::uint64_t> sent_{0};
  std::thread thread_;
};

// Pairs of 1024 Hz runs with the run secret, without and with the flood; the overruns' ratio.
void flood_pairs(const Args& a) {
  std::vector<double> quiet, flooded, quiet_command, flooded_command;
  const std::string rt = study_text(
      1.0 / 1024, a.seconds, std::string("deployment { clock: REAL_TIME ") + kUnjudged + "}");
  for (int r = 0; r < a.repeat; ++r)
    for (const bool flood : {false, true}) {
      std::optional<Flood> hostile;
      if (flood) hostile.emplace(a.domain + 1, a.flood_rate);
      const auto t0 = std::chrono::steady_clock::now();
      const auto f = run(a.domain + 1, rt, "flood" + std::to_string(r), false, true);
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double sent = hostile ? static_cast<double>(hostile->sent()) : 0.0;
      hostile.reset();
      const double pct = f.overruns_pct;
      (flood ? flooded : quiet).push_back(pct);
      (flood ? flooded_command : quiet_command).push_back(f.command_median_us);
      std::printf(
          "%s: overruns %.3f %%, wake-up to command median %.1f us; %.0f forged/s sent, "
          "%llu dropped unauthenticated\n",
          flood ? "flooded" : "quiet  ", pct, f.command_median_us, sent / seconds,
          static_cast<unsigned long long>(f.unauthenticated));
      std::fflush(stdout);
    }
  const auto m = [](const std::vector<double>& v) { return median(v); };
  std::printf(
      "  => medians of %d pairs (1024 Hz, %g s): overruns %.3f %% quiet, %.3f %% flooded (ratio "
      "%.2f); wake-up to command %.1f us quiet, %.1f us flooded\n",
      a.repeat, a.seconds, m(quiet), m(flooded), m(quiet) > 0 ? m(flooded) / m(quiet) : 0.0,
      m(quiet_command), m(flooded_command));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rths_secret_bench: the run secret's cost, and a flood's (not a test)"};
  Args a;
  bool secret = false, flood = false;
  app.add_flag("--secret-pairs", secret, "pairs without and with the run secret");
  app.add_flag("--flood-pairs", flood, "pairs of 1024 Hz runs without and with a flood");
  app.add_option("--repeat", a.repeat, "pairs (medians over them)")->check(CLI::PositiveNumber);
  app.add_option("--seconds", a.seconds, "s of record of the real-time runs");
  app.add_option("--domain", a.domain, "DDS domain ids D and D + 1 (default 195)");
  app.add_option("--flood-rate", a.flood_rate,
                 "forged messages per second (default 0: as fast as the writer goes; the "
                 "receiver's acknowledgements pace it, so a faster drop invites more)");
  CLI11_PARSE(app, argc, argv);
  if (secret == flood) {
    std::fprintf(stderr, "give one of --secret-pairs, --flood-pairs\n");
    return 2;
  }
  runtime::ensure_dds_config();
  spdlog::set_level(spdlog::level::warn);
  if (secret) secret_pairs(a);
  if (flood) flood_pairs(a);
  return 0;
}
