#pragma once
// A study judged by the RTHS benchmark problem's criteria (study.benchmark, Silva et al. 2020):
// every case but the reference, J1-J9 (core::benchmark_criteria) with
//   y_n  the command the integrator sent to the experimental DOF (SimulationResult::command),
//   x_m  the displacement the actuator measured there (SimulationResult::realised),
//   the numerical response (every DOF) against the exact linear response of the whole structure
//   (core::exact_linear_response of M, C, K before the split, same motion and dt).
// J1 is searched over +-j1_search (default 49 samples, as F4_evaluation.m searches 0..49).
// The table prints each case beside the published values of `published_case`, with the relative
// difference of J2-J9 and J1's difference in samples.

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/study_run.h"
#include "core/benchmark_criteria.h"

namespace rths::analysis {

struct BenchmarkCaseCriteria {
  std::string name;
  core::BenchmarkCriteria criteria;
};

struct BenchmarkEvaluation {
  std::vector<BenchmarkCaseCriteria> cases;
  std::vector<double> published;  // J1 (ms), J2-J9 (%); empty when none
  std::string published_case, published_source;
  double dt = 0.0;  // s
};

// Empty when the study has no `benchmark` section. Throws std::invalid_argument naming
// benchmark.experimental_dof or benchmark.published when they do not fit the structure.
std::optional<BenchmarkEvaluation> evaluate_benchmark(const core::PreparedStudy& prepared,
                                                      const StudyOutcome& outcome);

std::string benchmark_table(const BenchmarkEvaluation& evaluation);
nlohmann::json benchmark_json(const BenchmarkEvaluation& evaluation);

}  // namespace rths::analysis
