// DDS Security benchmark (not a test): the paper's frame in lockstep, coordinator + substructure
// node + actuator emulator as separate processes launched as `rths launch` does (one CPU), with
// DDS Security off and on (a fresh lab PKI: authentication, AES-GCM on discovery, liveliness,
// RTPS messages and data), alternating, `--repeats` times each. Prints per run the steps/s
// (steps / sum of the recorded step wall times) and the median step, then the medians and the
// ratio on / off of the median steps/s.
//
//   rths_security_bench [--seconds S (of the record, default 10)] [--repeats N (default 3)]
//                       [--domain D (D: off, D + 1: on; default 190)]
#include <CLI/CLI.hpp>

#include <unistd.h>
#include <cstdio>
#include <fstream>

#include "runtime/launch/launch.h"
#include "runtime/node/lag.h"
#include "runtime/record/record.h"
#include "security/pki.h"

namespace {

using namespace rths;
namespace fs = std::filesystem;

struct Figures {
  double steps_per_second = 0;
  double median_step = 0;  // s
  std::size_t steps = 0;
};

Figures lockstep_run(const fs::path& dir, int domain, double seconds, const fs::path& security) {
  const fs::path config = dir / "study.textproto";
  std::ofstream(config)
      << "name: \"bench\"\n"
         "structure { sdof { period: 0.5 mass: 1000 } damping { modal_zeta: 0.05 } }\n"
         "motion { path: \""
      << RTHS_DATA_DIR << "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2\" duration: " << seconds
      << " }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.001 }\n"
         "substructuring { experimental_fraction: 0.3333333333333333 model { linear {} } }\n"
         "cases { name: \"lag\" delay { shift { delay: 0.014 } } }\n";
  runtime::LaunchOptions options;
  options.config = config;
  options.case_name = "lag";
  options.domain = domain;
  options.programs_dir = RTHS_BINARY_DIR;
  options.record = dir / "run.rthsrec";
  options.log_dir = dir / "logs";
  options.timeout = 600;
  options.security_dir = security;
  const runtime::LaunchResult result = runtime::launch_run(options);
  if (result.coordinator_exit != 0)
    throw std::runtime_error("run failed (exit " + std::to_string(result.coordinator_exit) +
                             "); see " + result.coordinator_log.string());
  std::vector<double> walls;
  double total = 0;
  for (const auto* step : runtime::read_record(options.record).steps()) {
    if (step->step() == 0) continue;  // includes start-up
    walls.push_back(step->step_wall());
    total += step->step_wall();
  }
  return {static_cast<double>(walls.size()) / total, runtime::summarize(walls).median,
          walls.size()};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rths DDS Security benchmark"};
  double seconds = 10;
  int repeats = 3, domain = 190;
  app.add_option("--seconds", seconds, "s of the record per run (1 ms steps)");
  app.add_option("--repeats", repeats, "runs with security off and on each");
  app.add_option("--domain", domain, "DDS domain of the runs without security; +1 with");
  CLI11_PARSE(app, argc, argv);
  runtime::ensure_dds_config();
  const fs::path dir =
      fs::temp_directory_path() / ("rths_security_bench_" + std::to_string(getpid()));
  fs::remove_all(dir);
  security::init_pki(dir / "pki", {"rths-lab", 1, {{1, "substructure"}, {2, "actuator_emulator"}}});
  std::vector<double> off, on;
  for (int r = 0; r < repeats; ++r) {
    for (const bool secured : {false, true}) {
      const fs::path run_dir = dir / ((secured ? "on_" : "off_") + std::to_string(r));
      fs::create_directories(run_dir);
      const Figures f =
          lockstep_run(run_dir, domain + (secured ? 1 : 0), seconds, secured ? dir / "pki" : "");
      (secured ? on : off).push_back(f.steps_per_second);
      std::printf("run %d, security %-3s: %zu steps, %.0f steps/s, median step %.1f us\n", r + 1,
                  secured ? "on" : "off", f.steps, f.steps_per_second, f.median_step * 1e6);
      std::fflush(stdout);
    }
  }
  const double median_off = runtime::summarize(off).median;
  const double median_on = runtime::summarize(on).median;
  std::printf("lockstep steps/s, median of %d: security off %.0f, on %.0f; ratio on/off %.2f\n",
              repeats, median_off, median_on, median_on / median_off);
  fs::remove_all(dir);
  return 0;
}
