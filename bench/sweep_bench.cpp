// Sweep benchmark: linear SDOF periods 0.05..3.0 s under El Centro 1940 resampled to
// dt = 1 ms (31,180 steps each), peak |u| only (no histories kept), explicit Newmark.
//   (a) 100 periods, no delay
//   (b) the same 100 periods x 10 time-shift delays 0, 2, ..., 18 ms, alpha = 1
// Prints the median over repetitions of steps/s (lane steps: periods x delays x 31,180 per run),
// the ratio (b)/(a), and the peak RSS as the grid grows to 1000 and 10000 periods.
// Usage: sweep_bench [--threads N] [--repetitions R] [--skip-memory]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "analysis/sweep/batch_kernel.h"
#include "core/ground_motion.h"
#include "core/structure.h"
#include "study/motion_files.h"
#include "util/parallel_for.h"

namespace {

using rths::analysis::SdofLane;

constexpr double kDt = 0.001;
constexpr double kZeta = 0.05;

std::vector<SdofLane> lanes_for(std::size_t periods) {
  std::vector<SdofLane> lanes;
  for (std::size_t i = 0; i < periods; ++i) {
    const double period =
        0.05 + (3.0 - 0.05) * static_cast<double>(i) / static_cast<double>(periods - 1);
    const rths::core::StructuralModel model = rths::core::make_sdof(period, kZeta, 1.0);
    // alpha = 1: the whole storey is experimental, behind the delay.
    lanes.push_back({model.mass(0, 0), model.damping(0, 0), 0.0, model.storey_stiffness[0]});
  }
  return lanes;
}

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Medians over the repetitions of the wall time and of the CPU time summed over threads. The
// machine may be shared: CPU time shows what the kernel costs, wall time what a user waits.
struct Timing {
  double wall = 0, cpu = 0;
};

template <class Run>
Timing median_timing(int repetitions, Run run) {
  std::vector<double> wall, cpu;
  for (int r = 0; r < repetitions; ++r) {
    const double cpu_start = cpu_seconds();
    const auto start = std::chrono::steady_clock::now();
    run();
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    cpu.push_back(cpu_seconds() - cpu_start);
  }
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  return {wall[wall.size() / 2], cpu[cpu.size() / 2]};
}

double load_average() {
  double load = -1;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &load) != 1) load = -1;
    std::fclose(f);
  }
  return load;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 0, repetitions = 15;
  bool memory = true;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--threads") && i + 1 < argc)
      threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--repetitions") && i + 1 < argc)
      repetitions = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--skip-memory"))
      memory = false;
    else {
      std::fprintf(stderr, "usage: sweep_bench [--threads N] [--repetitions R] [--skip-memory]\n");
      return 2;
    }
  }
  const rths::core::GroundMotion record = rths::study::read_at2(
      std::string(RTHS_DATA_DIR) + "/ground_motions/elcentro_1940_ns_peknold.AT2");
  const rths::core::GroundMotion motion = rths::core::resampled(record, kDt);
  const double steps = static_cast<double>(motion.acceleration.size());
  rths::analysis::BatchRunOptions options;
  options.threads = rths::util::resolve_threads(threads);
  std::printf("sweep_bench: El Centro 1940 at dt = %g s: %zu steps per run; %d threads; %s\n", kDt,
              motion.acceleration.size(), options.threads,
              __builtin_cpu_supports("avx512f") ? "AVX-512 kernel"
              : __builtin_cpu_supports("avx2")  ? "AVX2 kernel"
                                                : "baseline kernel");

  const std::vector<SdofLane> lanes = lanes_for(100);
  std::vector<double> delays;
  for (int i = 0; i < 10; ++i) delays.push_back(0.002 * i);
  const std::vector<double> no_delay = {0.0};
  double sink = 0;

  const auto run_grid = [&](const std::vector<SdofLane>& grid, const std::vector<double>& d,
                            const rths::analysis::BatchRunOptions& o) {
    const auto out = rths::analysis::run_linear_sdof_grid(grid, d, motion.acceleration, kDt, o);
    sink += out[0][0].peak_abs;
  };
  rths::analysis::BatchRunOptions single = options;
  single.threads = 1;
  run_grid(lanes, delays, options);  // warm-up
  const Timing a1 = median_timing(repetitions, [&] { run_grid(lanes, no_delay, single); });
  const Timing a = median_timing(repetitions, [&] { run_grid(lanes, no_delay, options); });
  const Timing b = median_timing(repetitions, [&] { run_grid(lanes, delays, options); });
  const double rate_a1 = 100 * steps / a1.wall, rate_a = 100 * steps / a.wall,
               rate_b = 1000 * steps / b.wall;
  std::printf("load average before timing: %.2f (other processes share the cores)\n",
              load_average());
  std::printf(
      "median of %d runs; steps/s = lane steps / wall time; per CPU-s = / CPU time of all "
      "threads\n",
      repetitions);
  std::printf("(a)  100 periods, no delay, 1 thread : %8.3f ms  %.3e steps/s  %.3e per CPU-s\n",
              a1.wall * 1e3, rate_a1, 100 * steps / a1.cpu);
  std::printf(
      "(a)  100 periods, no delay           : %8.3f ms  %.3e steps/s  %.3e per CPU-s  (%.0fx "
      "OpenSees' 0.6e6)\n",
      a.wall * 1e3, rate_a, 100 * steps / a.cpu, rate_a / 0.6e6);
  std::printf("(b)  100 periods x 10 delays 0..18 ms: %8.3f ms  %.3e steps/s  %.3e per CPU-s\n",
              b.wall * 1e3, rate_b, 1000 * steps / b.cpu);
  std::printf(
      "(b)/(a) steps/s ratio: %.3f  (a lane step of (b) costs %.2fx one of (a); target <= 3x)\n",
      rate_b / rate_a, rate_a / rate_b);
  if (memory) {
    for (std::size_t periods : {100u, 1000u, 10000u}) {
      const std::vector<SdofLane> grid = lanes_for(periods);
      const auto start = std::chrono::steady_clock::now();
      run_grid(grid, delays, options);
      const double s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::printf("memory: %6zu periods x 10 delays: peak RSS %7.1f MiB  (%.3e steps/s)\n", periods,
                  peak_rss_mib(), static_cast<double>(periods) * 10 * steps / s);
    }
  }
  return sink == 12345.678 ? 1 : 0;  // keeps the results alive
}
