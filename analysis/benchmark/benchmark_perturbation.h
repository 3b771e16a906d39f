#pragma once
// The RTHS benchmark's perturbed plants (Silva et al. 2020, Table 2; F1_input_file.m), drawn from
// a seeded generator, and J1-J9 over the draws as mean +- standard deviation.
//
// A draw: four parameters, each normal around its nominal value (sd in brackets):
//   beta1 425 (3.3), beta2 9.9976e4 (3.3e3) 1/s, a3 3.3 (1.3) 1/s: the servo-valve and actuator;
//   k_e  the experimental DOF's stiffness in the study (5e4 N/m).
// perturbed_study() applies one draw to a copy of the study: every tracking loop's
// benchmark_plant takes beta1, beta2, a3 and k_e (its damping from zeta_e 0.0097 and k_e), and the
// experimental DOF (benchmark.experimental_dof) takes k_e, so the numerical part is K - K_e and
// C - C_e of the drawn specimen while the reference structure stays the same.
// Draws: std::mt19937_64 seeded with `seed`, std::normal_distribution, in the order
// beta1, beta2, a3, k_e per draw: the same draws on every run of one build.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/benchmark/benchmark_evaluation.h"
#include "rths/proto/config.pb.h"

namespace rths::analysis {

struct PlantDraw {
  double beta1 = 0.0, beta2 = 0.0, a3 = 0.0;  // -, 1/s, 1/s
  double stiffness = 0.0;                     // N/m, k_e
};

// @pre count >= 0; nominal_stiffness > 0 (N/m).
std::vector<PlantDraw> draw_benchmark_plants(int count, std::uint64_t seed,
                                             double nominal_stiffness);

// The study's experimental DOF's stiffness (N/m). Throws std::invalid_argument naming
// benchmark.experimental_dof when the study has no such experimental DOF.
double experimental_stiffness(const config::Study& study);

// The study with `draw` applied (above). Throws std::invalid_argument when the study has no
// benchmark section or its experimental DOF is not experimental.
config::Study perturbed_study(const config::Study& study, const PlantDraw& draw);

// Per case: mean and sample standard deviation (n - 1) of J1 (ms) and J2-J9 (%) over the draws.
struct CriteriaSpread {
  std::string name;
  std::array<double, 9> mean{}, std{};
  int draws = 0;
};
// @pre every evaluation lists the same cases in the same order.
std::vector<CriteriaSpread> criteria_spread(const std::vector<BenchmarkEvaluation>& draws);

std::string spread_table(const std::vector<CriteriaSpread>& spread, std::uint64_t seed);
nlohmann::json spread_json(const std::vector<CriteriaSpread>& spread, std::uint64_t seed);

}  // namespace rths::analysis
