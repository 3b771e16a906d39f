// Sparse-model benchmark (issues 48, 63): cost per step and before the first step of large models.
//   shear buildings of N = 10, 100, 1000, 10,000 floors given as Matrix Market files (diagonal
//     M = 1e5 kg per floor, tridiagonal K from storeys of 4e10 N/m, Rayleigh 5 % in modes 1 and
//     2), floor 1's DOF a third experimental (linear), explicit Newmark at dt = 1/1024 s, the
//     Imperial Valley record cut to 4 s: the study's own path, as `rths run` takes it (above
//     2,000 DOFs the model is held sparse only, from the file on). "Before the first step" is
//     prepare_study (read, check, damp, split, omega_max), the pre-run critical-delay check
//     (study/stability_config.h), the stability limit and run_steps up to its step 0 (integrator
//     factorised, initial state); "per step" the median of the loop's steps;
//   N = 1000 and 10,000 again with damping { modal_zeta: 0.05 }: modal damping through the
//     lowest modes, kept as a low-rank term (core::sparse_modal_damping), the model still sparse;
//   N = 300 condensed: a full (dense) K = A A^T + diagonal, as a condensed frame's is, through the
//     study's path (the fill rule keeps it dense).
// Columns: "loop step" is a step of core::run_steps (integrate, restoring force, and the row of
// every history the loop keeps: u, v, a of every DOF, stored column-major, so a row is n strided
// writes); "bare step" the integrator and restoring force alone (the coordinator's arithmetic).
// Every figure is a median over `--repetitions` runs (default 3) of the per-step medians; the
// load average is printed before and after, since this machine's cores are shared.
// Usage: sparse_bench [--repetitions R]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/simulation.h"
#include "core/sparse_structure.h"
#include "core/stability.h"
#include "study/stability_config.h"
#include "study/study.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using rths::core::Mat;
using rths::core::SparseMat;
using rths::core::Vec;

constexpr double kFloorMass = 1e5;         // kg
constexpr double kStoreyStiffness = 4e10;  // N/m: omega_max dt ~ 1.2 at dt = 1/1024 s
constexpr double kDt = 1.0 / 1024;

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values.empty() ? 0.0 : values[values.size() / 2];
}

// Lower triangle of a symmetric matrix as Matrix Market coordinate entries.
void write_market(const fs::path& path, int n, const std::vector<Eigen::Triplet<double>>& lower) {
  std::ofstream out(path);
  out << "%%MatrixMarket matrix coordinate real symmetric\n"
      << n << ' ' << n << ' ' << lower.size() << '\n';
  out.precision(17);
  for (const auto& t : lower) out << t.row() + 1 << ' ' << t.col() + 1 << ' ' << t.value() << '\n';
}

std::vector<Eigen::Triplet<double>> building_mass(int n) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, kFloorMass);
  return t;
}

std::vector<Eigen::Triplet<double>> building_stiffness(int n) {
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, i + 1 < n ? 2.0 * kStoreyStiffness : kStoreyStiffness);
    if (i > 0) t.emplace_back(i, i - 1, -kStoreyStiffness);
  }
  return t;
}

// K = A A^T + n k I with A uniform in [-k/n, k/n]^(n x n): full, as a condensed model's is.
std::vector<Eigen::Triplet<double>> condensed_stiffness(int n) {
  std::mt19937 rng(48);
  std::uniform_real_distribution<double> draw(-1.0, 1.0);
  Mat a(n, n);
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = draw(rng);
  const Mat k = (a * a.transpose() / n + n * Mat::Identity(n, n)) * (kStoreyStiffness / n);
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < n; ++j)
    for (int i = j; i < n; ++i) t.emplace_back(i, j, k(i, j));
  return t;
}

struct Figures {
  double before_first_step = 0.0;  // s
  double per_step = 0.0;           // s, median over the loop's steps (histories kept)
  double bare_step = 0.0;          // s, median of integrate + restoring force alone
  bool sparse = false;             // the model was held sparse
};

// The coordinator's step without the loop's histories: integrator and in-process restoring
// force only, over the motion.
double bare_step(const rths::core::HybridSetup& setup, const rths::core::GroundMotion& motion) {
  auto integrator = rths::core::make_integrator(setup.integrator, setup.model, setup.dt);
  rths::core::HybridRestoring restoring(setup.partition, {}, setup.dt);
  const Vec mass_iota = rths::core::mass_times(setup.model, setup.model.influence);
  const auto n = mass_iota.size();
  Vec load = Vec::Zero(n);
  integrator->initialize(Vec::Zero(n), Vec::Zero(n), Vec::Zero(n), load);
  std::vector<double> steps;
  for (std::size_t k = 1; k < motion.acceleration.size(); ++k) {
    const auto start = Clock::now();
    load = -mass_iota * motion.acceleration[k];
    restoring.set_time(static_cast<double>(k) * setup.dt);
    integrator->step(load, restoring);
    steps.push_back(std::chrono::duration<double>(Clock::now() - start).count());
  }
  return median(steps);
}

// Times before_step/after_step: step 0's end marks the first step's start.
class Timer final : public rths::core::StepHooks {
 public:
  explicit Timer(Clock::time_point start) : start_(start) {}
  void before_step(std::size_t) override { step_start_ = Clock::now(); }
  bool after_step(std::size_t k, const rths::core::SimulationResult&) override {
    const auto now = Clock::now();
    if (k == 0)
      first_ = std::chrono::duration<double>(now - start_).count();
    else
      steps_.push_back(std::chrono::duration<double>(now - step_start_).count());
    return true;
  }
  Figures figures() const { return {first_, median(steps_), 0.0, false}; }

 private:
  Clock::time_point start_, step_start_;
  double first_ = 0.0;
  std::vector<double> steps_;
};

constexpr const char* kRayleigh = "rayleigh { zeta: 0.05 mode_i: 1 mode_j: 2 }";
constexpr const char* kModal = "modal_zeta: 0.05";

std::string study_text(const std::string& motion, const std::string& damping) {
  return "name: \"sparse_bench\"\n"
         "structure { matrices { mass { file: \"mass.mtx\" } stiffness { file: \"stiffness.mtx\" "
         "} } damping { " +
         damping +
         " } }\n"
         "motion { path: \"" +
         motion +
         "\" duration: 4 }\n"
         "integrator { kind: EXPLICIT_NEWMARK dt: 0.0009765625 }\n"
         "substructuring { experimental_dofs { dof: 1 stiffness: " +
         std::to_string(kStoreyStiffness / 3) +
         " } }\n"
         "cases { name: \"reference\" }\n";
}

// The study's path: what `rths run` does before and during a case's loop.
Figures study_path(const fs::path& dir, const std::string& damping = kRayleigh) {
  const auto start = Clock::now();
  const std::string motion =
      std::string(RTHS_DATA_DIR) + "/ground_motions/RSN175_IMPVALL.H_H-E12140.AT2";
  const rths::config::Study study =
      rths::study::parse_study(study_text(motion, damping), "sparse_bench");
  const rths::study::PreparedStudy prepared = rths::study::prepare_study(study, dir);
  const rths::core::HybridSetup& setup = prepared.base;
  rths::study::check_lag_critical_delay(prepared, 0.01);
  rths::core::check_stability(setup.integrator, rths::core::max_omega(setup.model), setup.dt,
                              false);
  rths::core::HybridRestoring restoring(setup.partition, setup.delays, setup.dt);
  Timer timer(start);
  rths::core::SimulationResult result;
  rths::core::run_steps(setup, prepared.motion, restoring, timer, {}, result);
  Figures figures = timer.figures();
  figures.bare_step = bare_step(setup, prepared.motion);
  figures.sparse = setup.model.is_sparse();
  return figures;
}

Figures repeat(int repetitions, const std::function<Figures()>& run) {
  std::vector<double> first, step, bare;
  bool sparse = false;
  for (int r = 0; r < repetitions; ++r) {
    const Figures f = run();
    first.push_back(f.before_first_step);
    step.push_back(f.per_step);
    bare.push_back(f.bare_step);
    sparse = f.sparse;
  }
  return {median(first), median(step), median(bare), sparse};
}

void print_row(const char* model, int n, const Figures& f) {
  std::printf("%-24s %6d  %-6s %13.1f %13.2f %13.2f\n", model, n, f.sparse ? "sparse" : "dense",
              f.before_first_step * 1e3, f.per_step * 1e6, f.bare_step * 1e6);
}

}  // namespace

int main(int argc, char** argv) {
  int repetitions = 3;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--repetitions") == 0)
      repetitions = std::max(1, std::atoi(argv[i + 1]));
  const fs::path root =
      fs::temp_directory_path() / ("rths_sparse_bench_" + std::to_string(getpid()));
  std::printf("load average before: %s (1, 5, 15 min; other processes share the cores)\n",
              load_average().c_str());
  std::printf("%-24s %6s  %-6s %13s %13s %13s\n", "model", "DOFs", "held", "before 1st ms",
              "loop step us", "bare step us");
  for (int n : {10, 100, 1000, 10000}) {
    const fs::path dir = root / std::to_string(n);
    fs::create_directories(dir);
    write_market(dir / "mass.mtx", n, building_mass(n));
    write_market(dir / "stiffness.mtx", n, building_stiffness(n));
    print_row("shear building (.mtx)", n, repeat(repetitions, [&] { return study_path(dir); }));
  }
  for (int n : {1000, 10000})
    print_row("same, modal_zeta (.mtx)", n,
              repeat(repetitions, [&] { return study_path(root / std::to_string(n), kModal); }));
  const fs::path dense_dir = root / "condensed300";
  fs::create_directories(dense_dir);
  write_market(dense_dir / "mass.mtx", 300, building_mass(300));
  write_market(dense_dir / "stiffness.mtx", 300, condensed_stiffness(300));
  print_row("condensed frame (.mtx)", 300,
            repeat(repetitions, [&] { return study_path(dense_dir); }));
  fs::remove_all(root);
  std::printf("load average after: %s\n", load_average().c_str());
  return 0;
}
